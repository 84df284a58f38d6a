#include "tactile/plot/figure.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "tactile/plot/ticks.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/percentile.hpp"

namespace tactile::plot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTickFont = 0.4;
constexpr double kLabelFont = 0.5;
constexpr double kTitleFont = 0.55;
constexpr double kFigureTitleFont = 0.65;
constexpr int kMargin = 10;
constexpr int kTickLength = 4;
// Drawing coordinates carry 4 fractional bits (OpenCV's `shift`): sub-pixel placement of
// anti-aliased lines.
constexpr int kShift = 4;
constexpr double kSub = 16.0;

const Color kGridColor{225, 225, 225};
const Color kFrameColor{60, 60, 60};
const Color kTextColor{30, 30, 30};

cv::Scalar bgr(Color c) {
  return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)};
}

std::string printable(std::string s) {
  for (char& c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 32 || u > 126) c = '?';
  }
  return s;
}

struct TextBox {
  int w = 0;
  int h = 0;     // above the baseline
  int base = 0;  // below the baseline
};

TextBox measure(const std::string& s, double scale) {
  if (s.empty()) return {};
  int base = 0;
  const cv::Size sz = cv::getTextSize(printable(s), kFont, scale, 1, &base);
  return {sz.width, sz.height, base};
}

// Writes s with the point (ax, ay) of its box at (x, y): ax 0 = left edge, 0.5 = centre,
// 1 = right edge; ay 0 = top, 0.5 = middle, 1 = bottom (baseline).
void text_at(cv::Mat& img, const std::string& s, double x, double y, double ax, double ay,
             double scale, Color c) {
  if (s.empty()) return;
  const TextBox b = measure(s, scale);
  const int ox = static_cast<int>(std::lround(x - ax * b.w));
  const int oy = static_cast<int>(std::lround(y + (1 - ay) * b.h));
  cv::putText(img, printable(s), {ox, oy}, kFont, scale, bgr(c), 1, cv::LINE_AA);
}

// Vertical text reading bottom to top, centred on (cx, cy).
void text_vertical(cv::Mat& img, const std::string& s, double cx, double cy, double scale,
                   Color c) {
  if (s.empty()) return;
  const TextBox b = measure(s, scale);
  cv::Mat tile(b.h + b.base + 4, b.w + 4, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(tile, printable(s), {2, b.h + 2}, kFont, scale, bgr(c), 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(tile, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect r(static_cast<int>(std::lround(cx - turned.cols / 2.0)),
             static_cast<int>(std::lround(cy - turned.rows / 2.0)), turned.cols, turned.rows);
  const cv::Rect clipped = r & cv::Rect(0, 0, img.cols, img.rows);
  if (clipped.empty()) return;
  cv::Mat dst = img(clipped);
  const cv::Mat src =
      turned(cv::Rect(clipped.x - r.x, clipped.y - r.y, clipped.width, clipped.height));
  cv::min(dst, src, dst);  // dark text over a light background
}

bool shown(double v, Scale s) {
  return std::isfinite(v) && (s == Scale::kLinear || v > 0);
}

double to_axis(double v, Scale s) {
  return s == Scale::kLog ? std::log10(v) : v;
}

struct Extent {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v, Scale s) {
    if (!shown(v, s)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  void add(const Extent& e) {
    lo = std::min(lo, e.lo);
    hi = std::max(hi, e.hi);
  }
  bool empty() const { return !(lo <= hi); }
};

bool is_point_series(Series::Kind k) {
  return k == Series::Kind::kLine || k == Series::Kind::kScatter || k == Series::Kind::kStep;
}

struct DataExtent {
  Extent x;
  Extent y;
  bool bars_from_zero = false;  // a bar series starts at 0 on a linear y axis
};

// skip_points: only the series that are not lines, scatters or steps.
DataExtent extent_of(const Panel& p, bool skip_points = false) {
  const Scale xs = p.x_axis().scale;
  const Scale ys = p.y_axis().scale;
  DataExtent d;
  for (const Series& s : p.series()) {
    if (skip_points && is_point_series(s.kind)) continue;
    switch (s.kind) {
      case Series::Kind::kLine:
      case Series::Kind::kScatter:
      case Series::Kind::kStep:
        for (std::size_t i = 0; i < s.x.size(); ++i) {
          if (!shown(s.x[i], xs) || !shown(s.y[i], ys)) continue;
          d.x.add(s.x[i], xs);
          d.y.add(s.y[i], ys);
        }
        break;
      case Series::Kind::kBars:
        for (std::size_t i = 0; i < s.x.size(); ++i) {
          if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
          d.x.add(s.x[i] - s.u[i] / 2, xs);
          d.x.add(s.x[i] + s.u[i] / 2, xs);
          d.y.add(s.y[i], ys);
          if (ys == Scale::kLinear) {
            d.y.add(0.0, ys);
            d.bars_from_zero = true;
          }
        }
        break;
      case Series::Kind::kArrows:
        for (std::size_t i = 0; i < s.x.size(); ++i) {
          const double k = s.style.arrow_scale;
          const double x1 = s.x[i] + k * s.u[i];
          const double y1 = s.y[i] + k * s.v[i];
          if (!shown(s.x[i], xs) || !shown(s.y[i], ys) || !shown(x1, xs) || !shown(y1, ys))
            continue;
          d.x.add(s.x[i], xs);
          d.x.add(x1, xs);
          d.y.add(s.y[i], ys);
          d.y.add(y1, ys);
        }
        break;
      case Series::Kind::kVLine:
        d.x.add(s.x[0], xs);
        break;
      case Series::Kind::kHLine:
        d.y.add(s.y[0], ys);
        break;
      case Series::Kind::kBand:
        d.y.add(s.y[0], ys);
        d.y.add(s.y[1], ys);
        break;
      case Series::Kind::kCircle:
        if (!std::isfinite(s.x[0]) || !std::isfinite(s.y[0]) || !std::isfinite(s.u[0])) break;
        d.x.add(s.x[0] - s.u[0], xs);
        d.x.add(s.x[0] + s.u[0], xs);
        d.y.add(s.y[0] - s.u[0], ys);
        d.y.add(s.y[0] + s.u[0], ys);
        break;
    }
  }
  return d;
}

struct Range {
  double lo = 0;
  double hi = 1;
};

// A robust y axis: the quantile range of the points within the x range, widened by the margin,
// joined with everything that is not a point (thresholds, bands, bars, arrows, circles), which
// is always shown whole. The result is an extent in data units, without the usual 4 % margin.
Extent robust_y_extent(const Panel& p, Range x, Scale xs, const RobustRange& r) {
  const Scale ys = p.y_axis().scale;
  std::vector<double> v;
  for (const Series& s : p.series()) {
    if (!is_point_series(s.kind)) continue;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!shown(s.x[i], xs) || !shown(s.y[i], ys)) continue;
      if (s.x[i] < std::min(x.lo, x.hi) || s.x[i] > std::max(x.lo, x.hi)) continue;
      v.push_back(to_axis(s.y[i], ys));
    }
  }
  Extent e = extent_of(p, true).y;
  if (const auto q = robust_range(v, r)) {
    Extent qe;
    qe.lo = ys == Scale::kLog ? std::pow(10.0, q->first) : q->first;
    qe.hi = ys == Scale::kLog ? std::pow(10.0, q->second) : q->second;
    e.add(qe);
  }
  return e;
}

// The axis range: fixed ends where set, otherwise the data with a 4 % margin (none when `e`
// already has one: a robust range).
Range resolve(const Extent& e, const Panel::Axis& a, bool pin_zero, bool padded = true) {
  if (a.lo && a.hi) return {*a.lo, *a.hi};
  const bool log = a.scale == Scale::kLog;
  double lo = 0;
  double hi = 0;
  if (e.empty()) {
    lo = log ? 1 : 0;
    hi = log ? 10 : 1;
  } else {
    lo = to_axis(e.lo, a.scale);
    hi = to_axis(e.hi, a.scale);
    if (hi - lo <= std::abs(hi) * 1e-12) {
      const double pad = log ? 0.5 : (lo == 0 ? 1 : std::abs(lo) * 0.1);
      lo -= pad;
      hi += pad;
    } else {
      const double pad = padded ? 0.04 * (hi - lo) : 0.0;
      if (!(pin_zero && !log && e.lo == 0)) lo -= pad;
      hi += pad;
    }
    if (log) {
      lo = std::pow(10.0, lo);
      hi = std::pow(10.0, hi);
    }
  }
  if (a.lo) lo = *a.lo;
  if (a.hi) hi = *a.hi;
  if (!(lo < hi)) {  // one fixed end beyond the data
    if (a.lo) {
      hi = log ? lo * 10 : lo + 1;
    } else {
      lo = log ? hi / 10 : hi - 1;
    }
  }
  return {lo, hi};
}

std::vector<double> ticks_for(Range r, Scale s, int pixels, int spacing) {
  if (s == Scale::kLog) return log_ticks(r.lo, r.hi);
  return linear_ticks(r.lo, r.hi, std::max(2, pixels / spacing));
}

double tick_step(const std::vector<double>& ticks, Scale s) {
  if (s == Scale::kLog || ticks.size() < 2) return 0;
  return ticks[1] - ticks[0];
}

std::vector<std::string> tick_texts(const std::vector<double>& ticks, Scale s) {
  std::vector<std::string> out;
  const double step = tick_step(ticks, s);
  for (double t : ticks)
    out.push_back(format_tick(t, step));
  return out;
}

// --- geometry in pixels -------------------------------------------------------------------------

struct P {
  double x;
  double y;
};

// Clips the segment a-b to the rectangle [x0, x1] x [y0, y1] (Liang-Barsky); false when
// nothing is left.
bool clip(P& a, P& b, double x0, double y0, double x1, double y1) {
  double t0 = 0;
  double t1 = 1;
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a.x - x0, x1 - a.x, a.y - y0, y1 - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double r = q[i] / p[i];
    if (p[i] < 0) {
      t0 = std::max(t0, r);
    } else {
      t1 = std::min(t1, r);
    }
    if (t0 > t1) return false;
  }
  const P a0 = a;
  a = {a0.x + t0 * dx, a0.y + t0 * dy};
  b = {a0.x + t1 * dx, a0.y + t1 * dy};
  return true;
}

cv::Point sub(P p) {
  return {static_cast<int>(std::lround(p.x * kSub)), static_cast<int>(std::lround(p.y * kSub))};
}

// Draws on one panel's plot area, clipping everything to it.
class Canvas {
 public:
  Canvas(cv::Mat& img, const PanelLayout& l) : img_(img), l_(l) {}

  P map(double x, double y) const { return {l_.x_px(x), l_.y_px(y)}; }
  static bool ok(P p) { return std::isfinite(p.x) && std::isfinite(p.y); }

  void segment(P a, P b, Color c, int width) {
    if (!ok(a) || !ok(b)) return;
    const double m = width + 2.0;
    if (!clip(a, b, l_.left - m, l_.top - m, l_.right - 1 + m, l_.bottom - 1 + m)) return;
    cv::Mat roi = area();
    const P o{static_cast<double>(l_.left), static_cast<double>(l_.top)};
    cv::line(roi, sub({a.x - o.x, a.y - o.y}), sub({b.x - o.x, b.y - o.y}), bgr(c), width,
             cv::LINE_AA, kShift);
  }

  // A polyline in pixels; NaN points break it. Dashed: 8 px on, 5 px off along the path.
  void polyline(const std::vector<P>& pts, Color c, int width, bool dashed) {
    double phase = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) {
      const P pa = pts[i - 1];
      const P pb = pts[i];
      if (!ok(pa) || !ok(pb)) {
        phase = 0;
        continue;
      }
      if (!dashed) {
        segment(pa, pb, c, width);
        continue;
      }
      // Dash only the visible part: a long segment mostly off the panel would otherwise cost
      // one dash per 13 pixels of its whole length.
      P a = pa;
      P b = pb;
      const double m = width + 2.0;
      if (!clip(a, b, l_.left - m, l_.top - m, l_.right - 1 + m, l_.bottom - 1 + m)) {
        phase = 0;
        continue;
      }
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      double t = 0;
      while (t < len) {
        const double on = phase < 8 ? 8 - phase : 0;
        const double off = phase < 8 ? 5 : 13 - phase;
        // A phase a rounding error short of a dash's end (many short segments add it up) would
        // advance t by nothing, for ever: start the next part of the pattern instead.
        if (t + (on > 0 ? on : off) <= t) {
          phase = on > 0 ? 8 : 0;
          continue;
        }
        if (on > 0) {
          const double e = std::min(len, t + on);
          segment({a.x + (b.x - a.x) * t / len, a.y + (b.y - a.y) * t / len},
                  {a.x + (b.x - a.x) * e / len, a.y + (b.y - a.y) * e / len}, c, width);
          phase += e - t;
          t = e;
        } else {
          const double e = std::min(len, t + off);
          phase += e - t;
          t = e;
        }
        if (phase >= 13) phase -= 13;
      }
    }
  }

  void dot(P p, int radius, Color c) {
    if (!ok(p) || radius <= 0) return;
    if (p.x < l_.left - radius || p.x > l_.right + radius || p.y < l_.top - radius ||
        p.y > l_.bottom + radius)
      return;
    cv::Mat roi = area();
    cv::circle(roi, sub({p.x - l_.left, p.y - l_.top}), radius * 16, bgr(c), cv::FILLED,
               cv::LINE_AA, kShift);
  }

  void rect(P a, P b, Color fill, Color edge) {
    if (!ok(a) || !ok(b)) return;
    const double x0 = std::clamp(std::min(a.x, b.x), l_.left - 2.0, l_.right + 1.0);
    const double x1 = std::clamp(std::max(a.x, b.x), l_.left - 2.0, l_.right + 1.0);
    const double y0 = std::clamp(std::min(a.y, b.y), l_.top - 2.0, l_.bottom + 1.0);
    const double y1 = std::clamp(std::max(a.y, b.y), l_.top - 2.0, l_.bottom + 1.0);
    cv::Mat roi = area();
    const cv::Point p0(static_cast<int>(std::lround(x0)) - l_.left,
                       static_cast<int>(std::lround(y0)) - l_.top);
    const cv::Point p1(static_cast<int>(std::lround(x1)) - l_.left,
                       static_cast<int>(std::lround(y1)) - l_.top);
    cv::rectangle(roi, p0, p1, bgr(fill), cv::FILLED);
    if (p1.x - p0.x >= 3) cv::rectangle(roi, p0, p1, bgr(edge), 1);
  }

  void arrow(P a, P b, Color c, int width) {
    if (!ok(a) || !ok(b)) return;
    segment(a, b, c, width);
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (len < 1e-9) return;
    const double tip = std::min(0.35 * len, 4.0 + 2.0 * width);
    const double ux = (b.x - a.x) / len;
    const double uy = (b.y - a.y) / len;
    for (double side : {-1.0, 1.0}) {
      // 25 degrees either side of the shaft.
      const double ca = std::cos(25 * std::numbers::pi / 180);
      const double sa = side * std::sin(25 * std::numbers::pi / 180);
      const P t{b.x - tip * (ux * ca - uy * sa), b.y - tip * (uy * ca + ux * sa)};
      segment(b, t, c, width);
    }
  }

 private:
  cv::Mat area() const {
    return img_(cv::Rect(l_.left, l_.top, l_.right - l_.left, l_.bottom - l_.top));
  }
  cv::Mat& img_;
  const PanelLayout& l_;
};

Color darker(Color c) {
  return {static_cast<std::uint8_t>(c.r * 0.6), static_cast<std::uint8_t>(c.g * 0.6),
          static_cast<std::uint8_t>(c.b * 0.6)};
}

struct Box {
  int x0, y0, x1, y1;
  bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  bool inside(const PanelLayout& l) const {
    return x0 >= l.left && x1 <= l.right && y0 >= l.top && y1 <= l.bottom;
  }
};

// Geometry first for every series, then text on top (Pass::kText), so no line crosses a label.
enum class Pass { kGeometry, kText };

void draw_series(cv::Mat& img, const PanelLayout& l, const Series& s, std::vector<Box>& taken,
                 Pass pass) {
  Canvas cv(img, l);
  const bool geometry = pass == Pass::kGeometry;
  const bool has_text = s.kind == Series::Kind::kScatter || s.kind == Series::Kind::kVLine ||
                        s.kind == Series::Kind::kHLine || s.kind == Series::Kind::kBand ||
                        s.kind == Series::Kind::kBars;
  if (!geometry && !has_text) return;
  const int w = std::max(1, s.style.line_width);
  switch (s.kind) {
    case Series::Kind::kLine: {
      std::vector<P> pts;
      for (std::size_t i = 0; i < s.x.size(); ++i)
        pts.push_back(cv.map(s.x[i], s.y[i]));
      cv.polyline(pts, s.color, w, s.style.dashed);
      break;
    }
    case Series::Kind::kStep: {
      std::vector<P> pts;
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        const P p = cv.map(s.x[i], s.y[i]);
        if (!Canvas::ok(p)) {
          pts.push_back({kNaN, kNaN});
          continue;
        }
        if (!pts.empty() && Canvas::ok(pts.back())) pts.push_back({p.x, pts.back().y});
        pts.push_back(p);
      }
      cv.polyline(pts, s.color, w, s.style.dashed);
      break;
    }
    case Series::Kind::kScatter: {
      if (geometry) {
        for (std::size_t i = 0; i < s.x.size(); ++i)
          cv.dot(cv.map(s.x[i], s.y[i]), s.style.marker_radius, s.color);
        break;
      }
      for (std::size_t i = 0; i < s.texts.size() && i < s.x.size(); ++i) {
        const P p = cv.map(s.x[i], s.y[i]);
        if (!Canvas::ok(p) || s.texts[i].empty()) continue;
        if (p.x < l.left || p.x >= l.right || p.y < l.top || p.y >= l.bottom) continue;
        const TextBox b = measure(s.texts[i], kTickFont);
        const int r = s.style.marker_radius + 3;
        // Candidate places: right, left, above, below, then the diagonals further out.
        const std::array<std::array<double, 2>, 8> offsets{
            {{1, 0}, {-1, 0}, {0, -1}, {0, 1}, {1, -1.6}, {-1, -1.6}, {1, 1.6}, {-1, 1.6}}};
        Box chosen{};
        bool found = false;
        for (const auto& o : offsets) {
          const double cx = p.x + o[0] * (r + b.w / 2.0);
          const double cy = p.y + o[1] * (r + b.h / 2.0 + 1);
          const Box box{static_cast<int>(cx - b.w / 2.0) - 1, static_cast<int>(cy - b.h / 2.0) - 1,
                        static_cast<int>(cx + b.w / 2.0) + 1,
                        static_cast<int>(cy + b.h / 2.0 + b.base) + 1};
          if (!box.inside(l)) continue;
          if (std::any_of(taken.begin(), taken.end(),
                          [&](const Box& t) { return t.overlaps(box); }))
            continue;
          chosen = box;
          found = true;
          break;
        }
        if (!found) {
          const double cx =
              std::clamp(p.x + r + b.w / 2.0, l.left + b.w / 2.0, l.right - b.w / 2.0);
          chosen = {static_cast<int>(cx - b.w / 2.0), static_cast<int>(p.y - b.h / 2.0),
                    static_cast<int>(cx + b.w / 2.0), static_cast<int>(p.y + b.h / 2.0)};
        }
        taken.push_back(chosen);
        cv::rectangle(img, {chosen.x0, chosen.y0}, {chosen.x1, chosen.y1}, bgr(kWhite), cv::FILLED);
        text_at(img, s.texts[i], chosen.x0 + 1, chosen.y0 + 1, 0, 0, kTickFont, kTextColor);
      }
      break;
    }
    case Series::Kind::kBars: {
      if (!geometry) {
        // A histogram's values outside its range: the count at that edge, with an arrow.
        for (const bool high : {false, true}) {
          const std::size_t n = high ? s.beyond_range : s.below_range;
          if (n == 0) continue;
          const std::string text =
              high ? std::to_string(n) + " beyond ->" : "<- " + std::to_string(n) + " below";
          const TextBox b = measure(text, kTickFont);
          const int x0 = high ? l.right - 6 - b.w : l.left + 6;
          int y0 = l.top + 6;
          Box box{x0 - 2, y0 - 2, x0 + b.w + 2, y0 + b.h + b.base + 2};
          while (std::any_of(taken.begin(), taken.end(),
                             [&](const Box& t) { return t.overlaps(box); }) &&
                 box.y1 + b.h + 4 < l.bottom) {
            y0 += b.h + b.base + 3;
            box = {x0 - 2, y0 - 2, x0 + b.w + 2, y0 + b.h + b.base + 2};
          }
          taken.push_back(box);
          cv::rectangle(img, {box.x0, box.y0}, {box.x1, box.y1}, bgr(kWhite), cv::FILLED);
          text_at(img, text, x0, y0, 0, 0, kTickFont, darker(s.color));
        }
        break;
      }
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || !std::isfinite(s.u[i])) continue;
        const double base = l.y_scale == Scale::kLog ? l.y_lo : 0.0;
        if (l.y_scale == Scale::kLog && !(s.y[i] > 0)) continue;
        cv.rect(cv.map(s.x[i] - s.u[i] / 2, base), cv.map(s.x[i] + s.u[i] / 2, s.y[i]), s.color,
                darker(s.color));
      }
      break;
    }
    case Series::Kind::kArrows: {
      const double k = s.style.arrow_scale;
      for (std::size_t i = 0; i < s.x.size(); ++i)
        cv.arrow(cv.map(s.x[i], s.y[i]), cv.map(s.x[i] + k * s.u[i], s.y[i] + k * s.v[i]), s.color,
                 w);
      break;
    }
    case Series::Kind::kVLine: {
      const double px = l.x_px(s.x[0]);
      if (!std::isfinite(px)) break;
      if (geometry) {
        cv.polyline({{px, static_cast<double>(l.top)}, {px, l.bottom - 1.0}}, s.color, w,
                    s.style.dashed);
        break;
      }
      if (s.texts.empty() || s.texts[0].empty() || px < l.left || px >= l.right) break;
      const TextBox b = measure(s.texts[0], kTickFont);
      // Right of the line, or left of it near the right edge; lower while it would overlap.
      const bool right = px + 4 + b.w < l.right;
      int x0 = right ? static_cast<int>(px) + 4 : static_cast<int>(px) - 4 - b.w;
      x0 = std::max(x0, l.left);
      int y0 = l.top + 3;
      Box box{x0 - 1, y0 - 1, x0 + b.w + 1, y0 + b.h + b.base + 1};
      while (
          std::any_of(taken.begin(), taken.end(), [&](const Box& t) { return t.overlaps(box); }) &&
          box.y1 + b.h + 4 < l.bottom) {
        y0 += b.h + b.base + 3;
        box = {x0 - 1, y0 - 1, x0 + b.w + 1, y0 + b.h + b.base + 1};
      }
      taken.push_back(box);
      cv::rectangle(img, {box.x0, box.y0}, {box.x1, box.y1}, bgr(kWhite), cv::FILLED);
      text_at(img, s.texts[0], x0, y0, 0, 0, kTickFont, s.color);
      break;
    }
    case Series::Kind::kHLine: {
      const double py = l.y_px(s.y[0]);
      if (!std::isfinite(py)) break;
      if (geometry) {
        cv.polyline({{static_cast<double>(l.left), py}, {l.right - 1.0, py}}, s.color, w,
                    s.style.dashed);
        break;
      }
      if (s.texts.empty() || s.texts[0].empty() || py < l.top || py >= l.bottom) break;
      const TextBox b = measure(s.texts[0], kTickFont);
      const int x1 = l.right - 4;
      const int yb = static_cast<int>(py) - 3;
      const Box box{x1 - b.w - 2, yb - b.h - 2, x1 + 2, yb + b.base + 1};
      taken.push_back(box);
      cv::rectangle(img, {box.x0, box.y0}, {box.x1, box.y1}, bgr(kWhite), cv::FILLED);
      text_at(img, s.texts[0], x1, py - 3, 1, 1, kTickFont, s.color);
      break;
    }
    case Series::Kind::kBand: {
      const double p0 = l.y_px(s.y[0]);
      const double p1 = l.y_px(s.y[1]);
      if (!std::isfinite(p0) || !std::isfinite(p1)) break;
      const int top = std::clamp(static_cast<int>(std::lround(std::min(p0, p1))), l.top, l.bottom);
      const int bot = std::clamp(static_cast<int>(std::lround(std::max(p0, p1))), l.top, l.bottom);
      if (geometry) {
        if (bot > top) {
          // 20 % of the colour over what is below (grid lines stay visible through it).
          cv::Mat roi = img(cv::Rect(l.left, top, l.right - l.left, bot - top));
          cv::Mat fill(roi.size(), roi.type(), bgr(s.color));
          cv::addWeighted(roi, 0.8, fill, 0.2, 0, roi);
        }
        for (const double py : {p0, p1})
          cv.polyline({{static_cast<double>(l.left), py}, {l.right - 1.0, py}}, s.color,
                      std::max(1, s.style.line_width - 1), true);
        break;
      }
      if (s.texts.empty() || s.texts[0].empty()) break;
      const TextBox b = measure(s.texts[0], kTickFont);
      // Above the band's upper edge at the left, or inside it when there is no room above.
      const int x0 = l.left + 6;
      int y0 = top - 4 - b.h - b.base;
      if (y0 < l.top + 2) y0 = top + 3;
      const Box box{x0 - 2, y0 - 1, x0 + b.w + 2, y0 + b.h + b.base + 1};
      taken.push_back(box);
      cv::rectangle(img, {box.x0, box.y0}, {box.x1, box.y1}, bgr(kWhite), cv::FILLED);
      text_at(img, s.texts[0], x0, y0, 0, 0, kTickFont, darker(s.color));
      break;
    }
    case Series::Kind::kCircle: {
      if (!std::isfinite(s.u[0])) break;
      std::vector<P> pts;
      constexpr int kSides = 96;
      for (int i = 0; i <= kSides; ++i) {
        const double a = 2 * std::numbers::pi * i / kSides;
        pts.push_back(cv.map(s.x[0] + s.u[0] * std::cos(a), s.y[0] + s.u[0] * std::sin(a)));
      }
      cv.polyline(pts, s.color, w, s.style.dashed);
      break;
    }
  }
}

// Outlier markers: a filled triangle on the edge pointing out of the plot area; the counts in
// the top and bottom left corners.
void draw_outliers(cv::Mat& img, const PanelLayout& l, std::vector<Box>& taken) {
  for (const PanelLayout::Outlier& o : l.outliers) {
    const double dir = o.above ? 1.0 : -1.0;  // from the apex into the plot area
    const std::array<cv::Point, 3> tri{sub({o.x_px, o.y_px}), sub({o.x_px - 4, o.y_px + dir * 7}),
                                       sub({o.x_px + 4, o.y_px + dir * 7})};
    cv::fillConvexPoly(img, tri.data(), 3, bgr(darker(o.color)), cv::LINE_AA, kShift);
  }
  for (const bool above : {true, false}) {
    const std::size_t n = above ? l.above : l.below;
    if (n == 0) continue;
    const std::string text = std::to_string(n) + (n == 1 ? " point " : " points ") +
                             (above ? "above the axis (^)" : "below the axis (v)");
    const TextBox b = measure(text, kTickFont);
    const int x0 = l.left + 6;
    const int y0 = above ? l.top + 10 : l.bottom - 11 - b.h - b.base;
    const Box box{x0 - 2, y0 - 2, x0 + b.w + 2, y0 + b.h + b.base + 2};
    taken.push_back(box);
    cv::rectangle(img, {box.x0, box.y0}, {box.x1, box.y1}, bgr(kWhite), cv::FILLED);
    text_at(img, text, x0, y0, 0, 0, kTickFont, kTextColor);
  }
}

// How much a legend box would hide: data points (sampled every few pixels along lines and
// steps), threshold and event lines crossing it, and labels it would cover (the worst).
double legend_cost(const Box& box, const PanelLayout& l, const Panel& p,
                   const std::vector<Box>& taken) {
  double cost = 0;
  const auto inside = [&](P q) {
    return q.x >= box.x0 && q.x <= box.x1 && q.y >= box.y0 && q.y <= box.y1;
  };
  for (const Series& s : p.series()) {
    switch (s.kind) {
      case Series::Kind::kLine:
      case Series::Kind::kStep: {
        P prev{kNaN, kNaN};
        for (std::size_t i = 0; i < s.x.size(); ++i) {
          const P q{l.x_px(s.x[i]), l.y_px(s.y[i])};
          if (!Canvas::ok(q)) {
            prev = q;
            continue;
          }
          if (Canvas::ok(prev)) {
            // A step holds its value to the next point: sample the corner path.
            const P mid = s.kind == Series::Kind::kStep ? P{q.x, prev.y} : q;
            for (const auto& [a, b] : {std::pair{prev, mid}, std::pair{mid, q}}) {
              const double len = std::hypot(b.x - a.x, b.y - a.y);
              const int k = std::min(2000, static_cast<int>(len / 3));
              for (int j = 1; j <= k; ++j) {
                const double t = static_cast<double>(j) / (k + 1);
                if (inside({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)})) cost += 1;
              }
            }
          }
          if (inside(q)) cost += 1;
          prev = q;
        }
        break;
      }
      case Series::Kind::kScatter:
      case Series::Kind::kArrows:
        for (std::size_t i = 0; i < s.x.size(); ++i)
          if (inside({l.x_px(s.x[i]), l.y_px(s.y[i])})) cost += 3;
        break;
      case Series::Kind::kBars:
        for (std::size_t i = 0; i < s.x.size(); ++i) {
          const double x0 = l.x_px(s.x[i] - s.u[i] / 2);
          const double x1 = l.x_px(s.x[i] + s.u[i] / 2);
          const double y1 = l.y_px(s.y[i]);
          if (!std::isfinite(x0) || !std::isfinite(x1) || !std::isfinite(y1)) continue;
          const double w = std::min(x1, static_cast<double>(box.x1)) - std::max(x0, 1.0 * box.x0);
          const double h =
              std::min(l.bottom - 1.0, static_cast<double>(box.y1)) - std::max(y1, 1.0 * box.y0);
          if (w > 0 && h > 0) cost += w * h / 9;
        }
        break;
      case Series::Kind::kVLine: {
        const double x = l.x_px(s.x[0]);
        if (x >= box.x0 && x <= box.x1) cost += (box.y1 - box.y0) / 3.0;
        break;
      }
      case Series::Kind::kHLine: {
        const double y = l.y_px(s.y[0]);
        if (y >= box.y0 && y <= box.y1) cost += (box.x1 - box.x0) / 3.0;
        break;
      }
      case Series::Kind::kBand:
        for (const double v : s.y) {
          const double y = l.y_px(v);
          if (y >= box.y0 && y <= box.y1) cost += (box.x1 - box.x0) / 3.0;
        }
        break;
      case Series::Kind::kCircle:
        break;
    }
  }
  for (const Box& t : taken)
    if (t.overlaps(box)) cost += 1e6;
  for (const PanelLayout::Outlier& o : l.outliers)
    if (inside({o.x_px, o.y_px})) cost += 3;
  return cost;
}

void draw_legend(cv::Mat& img, const PanelLayout& l, const Panel& p,
                 const std::vector<Box>& taken) {
  if (!p.legend_corner()) return;
  std::vector<const Series*> entries;
  for (const Series& s : p.series())
    if (!s.label.empty()) entries.push_back(&s);
  if (entries.empty()) return;
  constexpr int kSample = 26;
  constexpr int kPad = 6;
  int text_w = 0;
  int row_h = 0;
  for (const Series* s : entries) {
    const TextBox b = measure(s->label, kTickFont);
    text_w = std::max(text_w, b.w);
    row_h = std::max(row_h, b.h + b.base + 4);
  }
  row_h = std::max(row_h, 14);
  const int w = kPad + kSample + 6 + text_w + kPad;
  const int h = kPad + row_h * static_cast<int>(entries.size()) + kPad - 4;
  const auto box_at = [&](Corner c) {
    const bool right = c == Corner::kTopRight || c == Corner::kBottomRight;
    const bool top = c == Corner::kTopRight || c == Corner::kTopLeft;
    const int bx = right ? l.right - 8 - w : l.left + 8;
    const int by = top ? l.top + 8 : l.bottom - 8 - h;
    return Box{bx, by, bx + w, by + h};
  };
  Corner c = *p.legend_corner();
  if (c == Corner::kBest) {
    double best = std::numeric_limits<double>::infinity();
    for (const Corner k :
         {Corner::kTopRight, Corner::kTopLeft, Corner::kBottomRight, Corner::kBottomLeft}) {
      const double cost = legend_cost(box_at(k), l, p, taken);
      if (cost < best) {
        best = cost;
        c = k;
      }
    }
  }
  const int x0 = box_at(c).x0;
  const int y0 = box_at(c).y0;
  cv::Mat roi = img(cv::Rect(0, 0, img.cols, img.rows));
  cv::rectangle(roi, {x0, y0}, {x0 + w, y0 + h}, bgr(kWhite), cv::FILLED);
  cv::rectangle(roi, {x0, y0}, {x0 + w, y0 + h}, bgr(Color{190, 190, 190}), 1);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Series& s = *entries[i];
    const double cy = y0 + kPad + row_h * (static_cast<double>(i) + 0.5) - 2;
    const double sx0 = x0 + kPad;
    const double sx1 = sx0 + kSample;
    const int lw = std::max(1, s.style.line_width);
    const auto line = [&](P a, P b) {
      cv::line(img, sub(a), sub(b), bgr(s.color), lw, cv::LINE_AA, kShift);
    };
    switch (s.kind) {
      case Series::Kind::kScatter:
        cv::circle(img, sub({(sx0 + sx1) / 2, cy}), std::max(2, s.style.marker_radius) * 16,
                   bgr(s.color), cv::FILLED, cv::LINE_AA, kShift);
        break;
      case Series::Kind::kBars:
        cv::rectangle(img, {static_cast<int>(sx0) + 4, static_cast<int>(cy) - 5},
                      {static_cast<int>(sx1) - 4, static_cast<int>(cy) + 5}, bgr(s.color),
                      cv::FILLED);
        break;
      case Series::Kind::kArrows:
        line({sx0, cy}, {sx1, cy});
        line({sx1, cy}, {sx1 - 7, cy - 4});
        line({sx1, cy}, {sx1 - 7, cy + 4});
        break;
      case Series::Kind::kCircle:
        cv::circle(img, sub({(sx0 + sx1) / 2, cy}), 6 * 16, bgr(s.color), lw, cv::LINE_AA, kShift);
        break;
      default:
        if (s.style.dashed) {
          line({sx0, cy}, {sx0 + 10, cy});
          line({sx0 + 16, cy}, {sx1, cy});
        } else {
          line({sx0, cy}, {sx1, cy});
        }
        break;
    }
    text_at(img, s.label, sx1 + 6, cy, 0, 0.5, kTickFont, kTextColor);
  }
}

// Points beyond the y range, within the x range: counted, and one marker per column and edge.
void find_outliers(const Panel& p, PanelLayout& l) {
  if (!p.y_axis().robust && !p.y_axis().outlier_markers) return;
  const double x0 = std::min(l.x_lo, l.x_hi);
  const double x1 = std::max(l.x_lo, l.x_hi);
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(std::max(l.right, 1)), 0);
  for (const Series& s : p.series()) {
    if (!is_point_series(s.kind)) continue;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!shown(s.x[i], l.x_scale) || !shown(s.y[i], l.y_scale)) continue;
      if (s.x[i] < x0 || s.x[i] > x1) continue;
      const bool above = s.y[i] > l.y_hi;
      if (!above && !(s.y[i] < l.y_lo)) continue;
      ++(above ? l.above : l.below);
      const double px = l.x_px(s.x[i]);
      const auto col = static_cast<std::size_t>(
          std::clamp(static_cast<long>(std::lround(px)), 0L, static_cast<long>(seen.size()) - 1));
      const std::uint8_t bit = above ? 1 : 2;
      if ((seen[col] & bit) != 0) continue;
      seen[col] |= bit;
      l.outliers.push_back(
          {px, above ? static_cast<double>(l.top) : l.bottom - 1.0, above, s.color});
    }
  }
}

}  // namespace

std::optional<std::pair<double, double>> robust_range(std::span<const double> values,
                                                      RobustRange r) {
  if (!(r.lo_quantile >= 0 && r.lo_quantile <= r.hi_quantile && r.hi_quantile <= 1) ||
      !(r.margin >= 0) || !std::isfinite(r.margin)) {
    throw std::invalid_argument(
        "robust range: quantiles must satisfy 0 <= lo <= hi <= 1 and "
        "the margin must be finite and >= 0");
  }
  std::vector<double> v;
  v.reserve(values.size());
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  if (v.empty()) return std::nullopt;
  std::sort(v.begin(), v.end());
  const double lo = r.lo_quantile == 0 ? v.front() : util::nearest_rank_of_sorted(v, r.lo_quantile);
  const double hi = util::nearest_rank_of_sorted(v, r.hi_quantile);
  const double pad = r.margin * (hi - lo);
  return std::pair{lo - pad, hi + pad};
}

// --- palette ------------------------------------------------------------------------------------

Color palette(std::size_t index) {
  static constexpr std::array<Color, 10> kColors{{{31, 119, 180},
                                                  {255, 127, 14},
                                                  {44, 160, 44},
                                                  {214, 39, 40},
                                                  {148, 103, 189},
                                                  {140, 86, 75},
                                                  {227, 119, 194},
                                                  {127, 127, 127},
                                                  {188, 189, 34},
                                                  {23, 190, 207}}};
  return kColors[index % kColors.size()];
}

// --- Panel --------------------------------------------------------------------------------------

Panel& Panel::title(std::string text) {
  title_ = std::move(text);
  return *this;
}
Panel& Panel::x_label(std::string text) {
  x_.label = std::move(text);
  return *this;
}
Panel& Panel::y_label(std::string text) {
  y_.label = std::move(text);
  return *this;
}
Panel& Panel::x_scale(Scale s) {
  x_.scale = s;
  return *this;
}
Panel& Panel::y_scale(Scale s) {
  y_.scale = s;
  return *this;
}

static void check_range(const char* axis, double lo, double hi, Scale s) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) {
    throw std::invalid_argument(std::string(axis) + " range must be finite with lo < hi, is [" +
                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  if (s == Scale::kLog && lo <= 0) {
    throw std::invalid_argument(std::string(axis) + " range on a log axis must be positive, is [" +
                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
}

Panel& Panel::x_range(double lo, double hi) {
  check_range("x", lo, hi, x_.scale);
  x_.lo = lo;
  x_.hi = hi;
  return *this;
}
Panel& Panel::y_range(double lo, double hi) {
  check_range("y", lo, hi, y_.scale);
  y_.lo = lo;
  y_.hi = hi;
  return *this;
}
Panel& Panel::y_robust(RobustRange r) {
  robust_range(std::span<const double>{}, r);  // checks r
  y_.robust = r;
  y_.outlier_markers = true;
  return *this;
}
Panel& Panel::outlier_markers(bool on) {
  y_.outlier_markers = on;
  return *this;
}
Panel& Panel::equal_aspect(bool on) {
  equal_aspect_ = on;
  return *this;
}
Panel& Panel::grid(bool on) {
  grid_ = on;
  return *this;
}
Panel& Panel::legend(Corner where) {
  legend_ = where;
  return *this;
}
Panel& Panel::no_legend() {
  legend_.reset();
  return *this;
}

Color Panel::next_color(const Style& style) {
  if (style.color) return *style.color;
  return palette(colors_used_++);
}

Panel& Panel::add(Series s) {
  series_.push_back(std::move(s));
  return *this;
}

static void check_sizes(const char* what, std::size_t a, std::size_t b) {
  if (a != b) {
    throw std::invalid_argument(std::string(what) + ": x has " + std::to_string(a) +
                                " values but y has " + std::to_string(b));
  }
}

static Series points(Series::Kind kind, std::span<const double> x, std::span<const double> y,
                     std::string label, const Style& style) {
  Series s;
  s.kind = kind;
  s.x.assign(x.begin(), x.end());
  s.y.assign(y.begin(), y.end());
  s.label = std::move(label);
  s.style = style;
  return s;
}

Panel& Panel::line(std::span<const double> x, std::span<const double> y, std::string label,
                   Style style) {
  check_sizes("line", x.size(), y.size());
  Series s = points(Series::Kind::kLine, x, y, std::move(label), style);
  s.color = next_color(style);
  return add(std::move(s));
}

Panel& Panel::scatter(std::span<const double> x, std::span<const double> y, std::string label,
                      Style style, std::vector<std::string> point_labels) {
  check_sizes("scatter", x.size(), y.size());
  if (!point_labels.empty() && point_labels.size() != x.size()) {
    throw std::invalid_argument("scatter: " + std::to_string(point_labels.size()) +
                                " point labels for " + std::to_string(x.size()) + " points");
  }
  Series s = points(Series::Kind::kScatter, x, y, std::move(label), style);
  s.texts = std::move(point_labels);
  s.color = next_color(style);
  return add(std::move(s));
}

Panel& Panel::step(std::span<const double> x, std::span<const double> y, std::string label,
                   Style style) {
  check_sizes("step", x.size(), y.size());
  Series s = points(Series::Kind::kStep, x, y, std::move(label), style);
  s.color = next_color(style);
  return add(std::move(s));
}

Panel& Panel::bars(std::span<const double> x, std::span<const double> height, double width,
                   std::string label, Style style) {
  check_sizes("bars", x.size(), height.size());
  if (!(width > 0) || !std::isfinite(width)) {
    throw std::invalid_argument("bars: width must be a positive number, is " +
                                std::to_string(width));
  }
  Series s = points(Series::Kind::kBars, x, height, std::move(label), style);
  s.u.assign(x.size(), width);
  s.color = next_color(style);
  return add(std::move(s));
}

Panel& Panel::histogram(std::span<const double> values, int bins, std::string label, Style style,
                        std::optional<double> lo, std::optional<double> hi) {
  if (bins < 1) throw std::invalid_argument("histogram: bins must be at least 1");
  Extent e;
  for (double v : values)
    e.add(v, Scale::kLinear);
  double a = lo.value_or(e.empty() ? 0.0 : e.lo);
  double b = hi.value_or(e.empty() ? 1.0 : e.hi);
  if (!std::isfinite(a) || !std::isfinite(b) || b < a) {
    throw std::invalid_argument("histogram: range must be finite with lo <= hi");
  }
  if (a == b) {
    a -= 0.5;
    b += 0.5;
  }
  const double width = (b - a) / bins;
  std::vector<double> centres(static_cast<std::size_t>(bins));
  std::vector<double> counts(static_cast<std::size_t>(bins), 0.0);
  for (int i = 0; i < bins; ++i)
    centres[static_cast<std::size_t>(i)] = a + (i + 0.5) * width;
  std::size_t below = 0;
  std::size_t beyond = 0;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    if (v < a || v > b) {
      ++(v < a ? below : beyond);
      continue;
    }
    const auto k =
        std::min(static_cast<std::size_t>((v - a) / width), static_cast<std::size_t>(bins - 1));
    counts[k] += 1;
  }
  bars(centres, counts, width, std::move(label), style);
  series_.back().below_range = below;
  series_.back().beyond_range = beyond;
  return *this;
}

Panel& Panel::histogram(std::span<const double> values, int bins, RobustRange range,
                        std::string label, Style style) {
  const auto r = robust_range(values, range);
  if (!r) return histogram(values, bins, std::move(label), style);
  // The margin widens the range towards the outliers, not below the smallest value or above the
  // largest: no empty bins beyond the data.
  const auto all = robust_range(values, RobustRange{0, 1, 0});
  const double lo = std::max(r->first, all->first);
  const double hi = std::min(r->second, all->second);
  return histogram(values, bins, std::move(label), style, lo, std::max(hi, lo));
}

Panel& Panel::arrows(std::span<const double> x, std::span<const double> y,
                     std::span<const double> dx, std::span<const double> dy, std::string label,
                     Style style) {
  check_sizes("arrows", x.size(), y.size());
  check_sizes("arrows (dx, dy)", dx.size(), dy.size());
  check_sizes("arrows (x, dx)", x.size(), dx.size());
  Series s = points(Series::Kind::kArrows, x, y, std::move(label), style);
  s.u.assign(dx.begin(), dx.end());
  s.v.assign(dy.begin(), dy.end());
  s.color = next_color(style);
  return add(std::move(s));
}

Panel& Panel::vline(double x, std::string text, Style style) {
  Series s;
  s.kind = Series::Kind::kVLine;
  s.x = {x};
  s.texts = {std::move(text)};
  s.style = style;
  s.color = style.color.value_or(kFrameColor);
  return add(std::move(s));
}

Panel& Panel::hline(double y, std::string text, Style style) {
  Series s;
  s.kind = Series::Kind::kHLine;
  s.y = {y};
  s.texts = {std::move(text)};
  s.style = style;
  s.color = style.color.value_or(kFrameColor);
  return add(std::move(s));
}

Panel& Panel::band(double lo, double hi, std::string text, Style style) {
  check_range("band", lo, hi, y_.scale);
  Series s;
  s.kind = Series::Kind::kBand;
  s.y = {lo, hi};
  s.texts = {std::move(text)};
  s.style = style;
  s.color = style.color.value_or(kGray);
  return add(std::move(s));
}

Panel& Panel::circle(double cx, double cy, double r, std::string label, Style style) {
  Series s;
  s.kind = Series::Kind::kCircle;
  s.x = {cx};
  s.y = {cy};
  s.u = {r};
  s.label = std::move(label);
  s.style = style;
  s.color = next_color(style);
  return add(std::move(s));
}

// --- layout -------------------------------------------------------------------------------------

double PanelLayout::x_px(double x) const {
  if (!shown(x, x_scale)) return kNaN;
  const double a = to_axis(x_lo, x_scale);
  const double b = to_axis(x_hi, x_scale);
  return left + (to_axis(x, x_scale) - a) / (b - a) * (right - 1 - left);
}

double PanelLayout::y_px(double y) const {
  if (!shown(y, y_scale)) return kNaN;
  const double a = to_axis(y_lo, y_scale);
  const double b = to_axis(y_hi, y_scale);
  return bottom - 1 - (to_axis(y, y_scale) - a) / (b - a) * (bottom - 1 - top);
}

Color Raster::at(int x, int y) const {
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                         static_cast<std::size_t>(x)) *
                        3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

Figure::Figure(int width_px, int height_px) : width_(width_px), height_(height_px) {
  if (width_px < 64 || height_px < 64 || width_px > 20000 || height_px > 20000) {
    throw std::invalid_argument("figure size must be 64..20000 pixels each way, is " +
                                std::to_string(width_px) + "x" + std::to_string(height_px));
  }
}

Figure& Figure::title(std::string text) {
  title_ = std::move(text);
  return *this;
}

Figure& Figure::share_x(bool on) {
  share_x_ = on;
  return *this;
}

Figure& Figure::fit_height_to_aspect(int max_height_px) {
  const double total_weight = std::accumulate(weights_.begin(), weights_.end(), 0.0);
  // The ranges each panel would have without the aspect (a copy with it off), and the plot area
  // the present height gives; a few rounds, as the tick labels' width moves the plot areas.
  for (int round = 0; round < 3; ++round) {
    Figure plain = *this;
    for (Panel& p : plain.panels_)
      p.equal_aspect(false);
    const std::vector<PanelLayout> ls = plain.layout();
    int areas = 0;
    double per_weight = 0;  // plot height per unit of share the most demanding panel needs
    for (std::size_t i = 0; i < ls.size(); ++i) {
      const PanelLayout& l = ls[i];
      areas += l.bottom - l.top;
      if (!panels_[i].has_equal_aspect() || l.x_scale != Scale::kLinear ||
          l.y_scale != Scale::kLinear)
        continue;
      const double need =
          (l.right - 1 - l.left) * (l.y_hi - l.y_lo) / (l.x_hi - l.x_lo) + 1;  // rows
      per_weight = std::max(per_weight, need / weights_[i]);
    }
    if (per_weight == 0) return *this;
    const int decoration = height_ - areas;
    height_ = std::clamp(decoration + static_cast<int>(std::ceil(per_weight * total_weight)), 64,
                         std::max(64, max_height_px));
  }
  return *this;
}

Panel& Figure::add_panel(double relative_height) {
  if (!(relative_height > 0) || !std::isfinite(relative_height)) {
    throw std::invalid_argument("relative_height must be a positive number");
  }
  panels_.emplace_back();
  weights_.push_back(relative_height);
  return panels_.back();
}

Panel& Figure::panel(std::size_t index) {
  if (index >= panels_.size()) {
    throw std::out_of_range("panel " + std::to_string(index) + " of " +
                            std::to_string(panels_.size()));
  }
  return panels_[index];
}

Figure& Figure::mark(double x, std::string text, Style style) {
  for (std::size_t i = 0; i < panels_.size(); ++i)
    panels_[i].vline(x, i == 0 ? text : std::string{}, style);
  return *this;
}

std::vector<PanelLayout> Figure::layout() const {
  const std::size_t n = panels_.size();
  std::vector<PanelLayout> out(n);
  if (n == 0) return out;

  std::vector<DataExtent> ext(n);
  for (std::size_t i = 0; i < n; ++i)
    ext[i] = extent_of(panels_[i]);
  // Shared x: the union of the data, or the first fixed range.
  std::optional<Range> shared;
  if (share_x_) {
    for (const Panel& p : panels_) {
      if (p.x_axis().lo && p.x_axis().hi) {
        shared = Range{*p.x_axis().lo, *p.x_axis().hi};
        break;
      }
    }
    if (!shared) {
      Extent all;
      for (const DataExtent& d : ext)
        all.add(d.x);
      Panel::Axis a = panels_[0].x_axis();
      shared = resolve(all, a, false);
    }
  }
  std::vector<Range> base_x(n);
  std::vector<Range> base_y(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Panel& p = panels_[i];
    PanelLayout& l = out[i];
    l.x_scale = shared ? panels_[0].x_axis().scale : p.x_axis().scale;
    l.y_scale = p.y_axis().scale;
    base_x[i] = shared ? *shared : resolve(ext[i].x, p.x_axis(), false);
    const auto& robust = p.y_axis().robust;
    const Extent ye = robust ? robust_y_extent(p, base_x[i], l.x_scale, *robust) : ext[i].y;
    base_y[i] = resolve(ye, p.y_axis(), ext[i].bars_from_zero, !robust);
  }

  const TextBox tick_box = measure("0123456789", kTickFont);
  const int tick_text_h = tick_box.h + tick_box.base;
  const TextBox label_box = measure("Xy", kLabelFont);
  const int label_h = label_box.h + label_box.base;
  const TextBox title_box = measure("Xy", kTitleFont);
  const int title_h = title_box.h + title_box.base;
  const TextBox fig_title_box = measure("Xy", kFigureTitleFont);
  const int top0 = kMargin + (title_.empty() ? 0 : fig_title_box.h + fig_title_box.base + 8);

  const auto shows_x_ticks = [&](std::size_t i) { return !share_x_ || i + 1 == n; };
  // Decoration heights above and below each plot area.
  std::vector<int> above(n);
  std::vector<int> below(n);
  int fixed = top0 + kMargin;
  for (std::size_t i = 0; i < n; ++i) {
    const Panel& p = panels_[i];
    above[i] = p.title_text().empty() ? 6 : title_h + 8;
    below[i] = 4;
    if (shows_x_ticks(i)) {
      below[i] = kTickLength + 3 + tick_text_h + 2;
      if (!p.x_axis().label.empty()) below[i] += label_h + 4;
    } else if (share_x_) {
      below[i] = 6;
    }
    fixed += above[i] + below[i];
  }
  const double total_weight = [&] {
    double s = 0;
    for (double w : weights_)
      s += w;
    return s;
  }();
  const int free_h = std::max(static_cast<int>(n) * 16, height_ - fixed);

  // Margins depend on the tick labels, which depend on the plot size: settle in a few rounds.
  int left_margin = kMargin + 40;
  int right_margin = kMargin + 6;
  for (int round = 0; round < 4; ++round) {
    int y = top0;
    int widest = 0;
    bool any_y_label = false;
    int wanted_right = kMargin + 6;
    for (std::size_t i = 0; i < n; ++i) {
      PanelLayout& l = out[i];
      const Panel& p = panels_[i];
      const int h = std::max(16, static_cast<int>(free_h * weights_[i] / total_weight));
      l.top = y + above[i];
      l.bottom = l.top + h;
      y = l.bottom + below[i];
      l.left = left_margin;
      l.right = std::max(l.left + 16, width_ - right_margin);
      l.x_lo = base_x[i].lo;
      l.x_hi = base_x[i].hi;
      l.y_lo = base_y[i].lo;
      l.y_hi = base_y[i].hi;
      if (p.has_equal_aspect() && l.x_scale == Scale::kLinear && l.y_scale == Scale::kLinear) {
        const double ux = (l.x_hi - l.x_lo) / (l.right - 1 - l.left);
        const double uy = (l.y_hi - l.y_lo) / (l.bottom - 1 - l.top);
        if (ux > uy || share_x_) {
          const double c = (l.y_lo + l.y_hi) / 2;
          const double half = ux * (l.bottom - 1 - l.top) / 2;
          l.y_lo = c - half;
          l.y_hi = c + half;
        } else {
          const double c = (l.x_lo + l.x_hi) / 2;
          const double half = uy * (l.right - 1 - l.left) / 2;
          l.x_lo = c - half;
          l.x_hi = c + half;
        }
      }
      l.x_ticks = ticks_for({l.x_lo, l.x_hi}, l.x_scale, l.right - l.left, 90);
      l.y_ticks = ticks_for({l.y_lo, l.y_hi}, l.y_scale, l.bottom - l.top, 45);
      for (const std::string& t : tick_texts(l.y_ticks, l.y_scale))
        widest = std::max(widest, measure(t, kTickFont).w);
      if (!p.y_axis().label.empty()) any_y_label = true;
      if (shows_x_ticks(i) && !l.x_ticks.empty()) {
        const auto texts = tick_texts(l.x_ticks, l.x_scale);
        const double last_px = l.x_px(l.x_ticks.back());
        const double overhang = last_px + measure(texts.back(), kTickFont).w / 2.0 - (l.right - 1);
        wanted_right = std::max(wanted_right, kMargin + static_cast<int>(std::ceil(overhang)));
      }
    }
    const int wanted_left = kMargin + (any_y_label ? label_h + 6 : 0) + widest + kTickLength + 4;
    if (wanted_left == left_margin && wanted_right == right_margin) break;
    left_margin = wanted_left;
    right_margin = wanted_right;
  }
  // A picture too small for its decorations still gets plot areas inside it.
  for (PanelLayout& l : out) {
    l.left = std::clamp(l.left, 0, width_ - 2);
    l.right = std::clamp(l.right, l.left + 2, width_);
    l.top = std::clamp(l.top, 0, height_ - 2);
    l.bottom = std::clamp(l.bottom, l.top + 2, height_);
  }
  for (std::size_t i = 0; i < n; ++i)
    find_outliers(panels_[i], out[i]);
  return out;
}

Raster Figure::render() const {
  cv::Mat img(height_, width_, CV_8UC3, cv::Scalar(255, 255, 255));
  const std::vector<PanelLayout> lay = layout();
  if (!title_.empty())
    text_at(img, title_, width_ / 2.0, kMargin, 0.5, 0, kFigureTitleFont, kTextColor);
  const std::size_t n = panels_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Panel& p = panels_[i];
    const PanelLayout& l = lay[i];
    const bool x_texts = !share_x_ || i + 1 == n;
    // Grid.
    if (p.has_grid()) {
      for (double t : l.x_ticks) {
        const int px = static_cast<int>(std::lround(l.x_px(t)));
        if (px > l.left && px < l.right - 1)
          cv::line(img, {px, l.top}, {px, l.bottom - 1}, bgr(kGridColor), 1);
      }
      for (double t : l.y_ticks) {
        const int py = static_cast<int>(std::lround(l.y_px(t)));
        if (py > l.top && py < l.bottom - 1)
          cv::line(img, {l.left, py}, {l.right - 1, py}, bgr(kGridColor), 1);
      }
    }
    // Series, then the frame over their clipped ends.
    std::vector<Box> taken;
    for (const Series& s : p.series())
      if (s.kind == Series::Kind::kBand) draw_series(img, l, s, taken, Pass::kGeometry);
    for (const Series& s : p.series())
      if (s.kind != Series::Kind::kBand) draw_series(img, l, s, taken, Pass::kGeometry);
    draw_outliers(img, l, taken);
    for (const Series& s : p.series())
      draw_series(img, l, s, taken, Pass::kText);
    cv::rectangle(img, {l.left - 1, l.top - 1}, {l.right, l.bottom}, bgr(kFrameColor), 1);
    // Ticks and their labels.
    const auto xt = tick_texts(l.x_ticks, l.x_scale);
    for (std::size_t k = 0; k < l.x_ticks.size(); ++k) {
      const int px = static_cast<int>(std::lround(l.x_px(l.x_ticks[k])));
      cv::line(img, {px, l.bottom}, {px, l.bottom + kTickLength}, bgr(kFrameColor), 1);
      if (x_texts)
        text_at(img, xt[k], px, l.bottom + kTickLength + 3, 0.5, 0, kTickFont, kTextColor);
    }
    const auto yt = tick_texts(l.y_ticks, l.y_scale);
    for (std::size_t k = 0; k < l.y_ticks.size(); ++k) {
      const int py = static_cast<int>(std::lround(l.y_px(l.y_ticks[k])));
      cv::line(img, {l.left - 1 - kTickLength, py}, {l.left - 1, py}, bgr(kFrameColor), 1);
      text_at(img, yt[k], l.left - kTickLength - 4, py, 1, 0.5, kTickFont, kTextColor);
    }
    // Labels and title.
    if (x_texts && !p.x_axis().label.empty()) {
      const TextBox tb = measure("0", kTickFont);
      text_at(img, p.x_axis().label, (l.left + l.right) / 2.0,
              l.bottom + kTickLength + 3 + tb.h + tb.base + 4, 0.5, 0, kLabelFont, kTextColor);
    }
    if (!p.y_axis().label.empty()) {
      const TextBox lb = measure("Xy", kLabelFont);
      text_vertical(img, p.y_axis().label, kMargin + (lb.h + lb.base) / 2.0,
                    (l.top + l.bottom) / 2.0, kLabelFont, kTextColor);
    }
    if (!p.title_text().empty())
      text_at(img, p.title_text(), (l.left + l.right) / 2.0, l.top - 5, 0.5, 1, kTitleFont,
              kTextColor);
    draw_legend(img, l, p, taken);
  }
  Raster r;
  r.width = width_;
  r.height = height_;
  cv::Mat rgb;
  cv::cvtColor(img, rgb, cv::COLOR_BGR2RGB);
  r.rgb.assign(rgb.datastart, rgb.dataend);
  return r;
}

std::string Figure::png() const {
  const Raster r = render();
  cv::Mat rgb(r.height, r.width, CV_8UC3, const_cast<std::uint8_t*>(r.rgb.data()));
  cv::Mat bgr_img;
  cv::cvtColor(rgb, bgr_img, cv::COLOR_RGB2BGR);
  std::vector<std::uint8_t> buf;
  if (!cv::imencode(".png", bgr_img, buf)) throw std::runtime_error("PNG encoding failed");
  return {buf.begin(), buf.end()};
}

void Figure::save_png(const std::filesystem::path& path) const {
  const std::string bytes = png();
  try {
    util::write_file_atomic(path, bytes);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot write plot " + path.string() + ": " + e.what());
  }
}

}  // namespace tactile::plot
