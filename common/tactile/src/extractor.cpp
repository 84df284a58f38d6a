#include "tactile/extractor.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "disk.hpp"

namespace tactile {
namespace {

// Increments and weights are fixed point with 8 fractional bits (Q8): the reference mean of N
// frames keeps sub-gray-level precision and every sum stays an exact 64-bit integer.
constexpr int kQBits = 8;
constexpr double kQ = 256.0;

template <typename Pixel>
constexpr std::int32_t q8(Pixel p) {
  return static_cast<std::int32_t>(p) << kQBits;
}

double soft_edge(double half_width, double distance) {
  return std::clamp(half_width + 0.5 - std::abs(distance), 0.0, 1.0);
}

}  // namespace

const char* to_string(CentroidEstimator e) {
  switch (e) {
    case CentroidEstimator::kPlain:
      return "plain";
    case CentroidEstimator::kThresholded:
      return "thresholded";
    case CentroidEstimator::kWindowed:
      return "windowed";
    case CentroidEstimator::kGaussian:
      return "gaussian";
  }
  return "unknown";
}

std::optional<CentroidEstimator> parse_estimator(std::string_view name) {
  for (auto e : {CentroidEstimator::kPlain, CentroidEstimator::kThresholded,
                 CentroidEstimator::kWindowed, CentroidEstimator::kGaussian}) {
    if (name == to_string(e)) return e;
  }
  return std::nullopt;
}

const char* to_string(MeasureStatus s) {
  switch (s) {
    case MeasureStatus::kOk:
      return "ok";
    case MeasureStatus::kNoReference:
      return "no reference";
    case MeasureStatus::kWrongSize:
      return "frame size differs from the calibration";
    case MeasureStatus::kWrongFormat:
      return "pixel format differs from the calibration";
  }
  return "unknown";
}

const char* to_string(ReferenceStatus s) {
  switch (s) {
    case ReferenceStatus::kCollecting:
      return "collecting";
    case ReferenceStatus::kComplete:
      return "complete";
    case ReferenceStatus::kRefusedMotion:
      return "refused: a frame changed while capturing (the sensor is being touched)";
    case ReferenceStatus::kRefusedLoad:
      return "refused: the sensor is loaded (against the previous reference)";
    case ReferenceStatus::kRefusedSpot:
      return "refused: an element shows a contact spot";
    case ReferenceStatus::kWrongSize:
      return "refused: frame size differs from the calibration";
    case ReferenceStatus::kWrongFormat:
      return "refused: pixel format differs from the calibration";
    case ReferenceStatus::kNoFrames:
      return "refused: no frames";
  }
  return "unknown";
}

Extractor::Extractor(Calibration cal, ExtractorOptions options)
    : cal_(std::move(cal)), opt_(options) {
  validate(cal_);
  if (opt_.reference_frames < 1 || opt_.reference_frames > 65536) {
    throw std::invalid_argument("reference_frames must be 1..65536, is " +
                                std::to_string(opt_.reference_frames));
  }
  if (opt_.max_gap_frames < 1) throw std::invalid_argument("max_gap_frames must be at least 1");
  if (!std::isfinite(opt_.window_margin_px) || opt_.window_margin_px < 0) {
    throw std::invalid_argument("window_margin_px must be a non-negative number");
  }
  if (!std::isfinite(opt_.gaussian_reach_sigmas) || opt_.gaussian_reach_sigmas < 1) {
    throw std::invalid_argument("gaussian_reach_sigmas must be at least 1");
  }
  floor_q_ = static_cast<std::int32_t>(std::lround(cal_.noise_floor * kQ));

  std::uint32_t offset = 0;
  layout_.reserve(cal_.elements.size());
  for (const ElementCalibration& e : cal_.elements) {
    ElementLayout el{};
    el.span_begin = static_cast<std::uint32_t>(spans_.size());
    el.origin_x = std::numeric_limits<std::int32_t>::max();
    for_each_disk_row(e.center_px, e.radius_px, [&](int y, int x0, int x1) {
      spans_.push_back({y, x0, x1, offset});
      offset += static_cast<std::uint32_t>(x1 - x0);
      el.origin_x = std::min(el.origin_x, x0);
    });
    el.span_end = static_cast<std::uint32_t>(spans_.size());
    el.origin_y = spans_[el.span_begin].y;
    layout_.push_back(el);
  }
  ref_q_.assign(offset, 0);
  int max_side = 1;
  for (const ElementCalibration& e : cal_.elements) {
    max_side = std::max(max_side, static_cast<int>(2 * std::ceil(e.radius_px)) + 3);
  }
  wx_.assign(static_cast<std::size_t>(max_side), 0.0);
  wxu_ = wx_;
  wxu2_ = wx_;
  wy_ = wx_;
  capture_sum_.assign(static_cast<std::size_t>(cal_.width) * static_cast<std::size_t>(cal_.height),
                      0);
  state_.assign(cal_.elements.size(), ElementState{});
  readings_.assign(cal_.elements.size(), ElementReading{});
  for (std::size_t i = 0; i < readings_.size(); ++i)
    readings_[i].id = cal_.elements[i].id;
}

bool Extractor::geometry_matches(const ImageView& f) const {
  return f.data != nullptr && f.width == cal_.width && f.height == cal_.height &&
         f.stride_bytes >= static_cast<std::size_t>(f.width) * bytes_per_pixel(f.format);
}

// --- reference ----------------------------------------------------------------------------------

void Extractor::begin_reference() {
  std::fill(capture_sum_.begin(), capture_sum_.end(), 0U);
  capture_frames_ = 0;
}

ReferenceResult Extractor::refuse(ReferenceStatus s, std::uint32_t id, double value) {
  ReferenceResult r{s, capture_frames_, id, value};
  begin_reference();
  return r;
}

ReferenceResult Extractor::add_reference_frame(const ImageView& f) {
  if (!geometry_matches(f)) return refuse(ReferenceStatus::kWrongSize, 0, 0);
  if (bit_depth(f.format) != cal_.bit_depth) return refuse(ReferenceStatus::kWrongFormat, 0, 0);

  const auto w = static_cast<std::size_t>(cal_.width);
  if (capture_frames_ > 0) {
    // Motion check: no element may change by a contact's worth against the running mean.
    const auto n = static_cast<std::uint64_t>(capture_frames_);
    for (std::size_t i = 0; i < layout_.size(); ++i) {
      const ElementLayout& el = layout_[i];
      std::int64_t up = 0;
      std::int64_t down = 0;
      for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
        const Span& sp = spans_[s];
        for (int x = sp.x0; x < sp.x1; ++x) {
          const std::uint64_t sum = capture_sum_[static_cast<std::size_t>(sp.y) * w + x];
          const auto mean_q = static_cast<std::int64_t>((sum * 256U + n / 2) / n);
          const std::int64_t d = static_cast<std::int64_t>(q8(f.at(x, sp.y))) - mean_q;
          up += std::max<std::int64_t>(d - floor_q_, 0);
          down += std::max<std::int64_t>(-d - floor_q_, 0);
        }
      }
      const double change = static_cast<double>(std::max(up, down)) / kQ;
      if (change >= cal_.contact_on) {
        return refuse(ReferenceStatus::kRefusedMotion, cal_.elements[i].id, change);
      }
    }
  }
  for (int y = 0; y < cal_.height; ++y) {
    std::uint32_t* sum = capture_sum_.data() + static_cast<std::size_t>(y) * w;
    if (f.format == PixelFormat::kMono8) {
      const auto* row = f.row<std::uint8_t>(y);
      for (int x = 0; x < cal_.width; ++x)
        sum[x] += row[x];
    } else {
      const auto* row = f.row<std::uint16_t>(y);
      for (int x = 0; x < cal_.width; ++x)
        sum[x] += row[x];
    }
  }
  ++capture_frames_;
  if (capture_frames_ >= opt_.reference_frames) return complete_reference();
  return {ReferenceStatus::kCollecting, capture_frames_, 0, 0};
}

ReferenceResult Extractor::finish_reference() {
  return complete_reference();
}

ReferenceResult Extractor::complete_reference() {
  if (capture_frames_ == 0) return refuse(ReferenceStatus::kNoFrames, 0, 0);
  const auto n = static_cast<std::uint64_t>(capture_frames_);
  const auto w = static_cast<std::size_t>(cal_.width);
  std::vector<std::int32_t> mean_q(ref_q_.size());
  for (const Span& sp : spans_) {
    for (int x = sp.x0; x < sp.x1; ++x) {
      const std::uint64_t sum = capture_sum_[static_cast<std::size_t>(sp.y) * w + x];
      mean_q[sp.ref_offset + static_cast<std::uint32_t>(x - sp.x0)] =
          static_cast<std::int32_t>((sum * 256U + n / 2) / n);
    }
  }

  for (std::size_t i = 0; i < layout_.size(); ++i) {
    const ElementLayout& el = layout_[i];
    const ElementCalibration& ec = cal_.elements[i];
    if (has_reference_) {
      std::int64_t load = 0;
      for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
        const Span& sp = spans_[s];
        for (std::uint32_t k = sp.ref_offset;
             k < sp.ref_offset + static_cast<std::uint32_t>(sp.x1 - sp.x0); ++k) {
          load += std::max<std::int64_t>(
              static_cast<std::int64_t>(mean_q[k]) - ref_q_[k] - floor_q_, 0);
        }
      }
      const double g = static_cast<double>(load) / kQ;
      if (g >= cal_.contact_on) return refuse(ReferenceStatus::kRefusedLoad, ec.id, g);
    }
    // Spot check: the inner disk may not stand above the rim ring by a contact's worth. A smooth
    // (vignetted) background has no such excess; a pressed element does. Tiny disks are skipped.
    if (opt_.reference_spot_check && ec.radius_px >= 3.0) {
      const double r_inner = 0.6 * ec.radius_px;
      const double r_rim = 0.8 * ec.radius_px;
      std::int64_t rim_sum = 0;
      std::int64_t rim_n = 0;
      std::int64_t inner_sum = 0;
      std::int64_t inner_n = 0;
      for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
        const Span& sp = spans_[s];
        for (int x = sp.x0; x < sp.x1; ++x) {
          const double r = std::hypot(x - ec.center_px.x, sp.y - ec.center_px.y);
          const std::int32_t v = mean_q[sp.ref_offset + static_cast<std::uint32_t>(x - sp.x0)];
          if (r <= r_inner) {
            inner_sum += v;
            ++inner_n;
          } else if (r >= r_rim) {
            rim_sum += v;
            ++rim_n;
          }
        }
      }
      if (inner_n > 0 && rim_n > 0) {
        const double rim_mean = static_cast<double>(rim_sum) / static_cast<double>(rim_n);
        const double excess =
            (static_cast<double>(inner_sum) - rim_mean * static_cast<double>(inner_n)) / kQ;
        if (excess >= cal_.contact_on) return refuse(ReferenceStatus::kRefusedSpot, ec.id, excess);
      }
    }
  }

  ref_q_ = std::move(mean_q);
  const PixelFormat fmt = cal_.bit_depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
  reference_image_ = Image(cal_.width, cal_.height, fmt);
  for (int y = 0; y < cal_.height; ++y) {
    for (int x = 0; x < cal_.width; ++x) {
      const std::uint64_t sum = capture_sum_[static_cast<std::size_t>(y) * w + x];
      reference_image_.set(x, y, static_cast<std::uint32_t>((sum + n / 2) / n));
    }
  }
  has_reference_ = true;
  const int frames = capture_frames_;
  begin_reference();
  std::fill(state_.begin(), state_.end(), ElementState{});
  forget_previous();
  return {ReferenceStatus::kComplete, frames, 0, 0};
}

// --- per frame ----------------------------------------------------------------------------------

void Extractor::forget_previous() noexcept {
  has_previous_ = false;
}

template <typename Pixel, bool kPlainWeights>
static void accumulate(const Pixel* row, const std::int32_t* ref, int x0, int x1, int origin_x,
                       std::int32_t floor_q, std::int64_t& g, std::int64_t& c0, std::int64_t& cx,
                       std::int64_t& above, std::int32_t& peak) noexcept {
  std::int64_t rg = 0;
  std::int64_t rc = 0;
  std::int64_t rcx = 0;
  std::int64_t ra = 0;
  std::int32_t rp = peak;
  for (int x = x0; x < x1; ++x) {
    const std::int32_t d = q8(row[x]) - ref[x - x0];
    const std::int32_t w = std::max(d - floor_q, 0);
    const std::int32_t wc = kPlainWeights ? std::max(d, 0) : w;
    rg += w;
    rc += wc;
    rcx += static_cast<std::int64_t>(wc) * (x - origin_x);
    ra += wc > 0 ? 1 : 0;
    rp = std::max(rp, d);
  }
  g += rg;
  c0 += rc;
  cx += rcx;
  above += ra;
  peak = rp;
}

template <typename Pixel>
Extractor::Moments Extractor::first_pass(const ElementLayout& el,
                                         const ImageView& f) const noexcept {
  Moments m;
  const bool plain = opt_.estimator == CentroidEstimator::kPlain;
  for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
    const Span& sp = spans_[s];
    const Pixel* row = f.row<Pixel>(sp.y);
    const std::int32_t* ref = ref_q_.data() + sp.ref_offset;
    const std::int64_t c0_before = m.c0;
    if (plain) {
      accumulate<Pixel, true>(row, ref, sp.x0, sp.x1, el.origin_x, floor_q_, m.g, m.c0, m.cx,
                              m.above, m.peak);
    } else {
      accumulate<Pixel, false>(row, ref, sp.x0, sp.x1, el.origin_x, floor_q_, m.g, m.c0, m.cx,
                               m.above, m.peak);
    }
    m.cy += (m.c0 - c0_before) * (sp.y - el.origin_y);
  }
  return m;
}

template <typename Pixel>
bool Extractor::windowed_pass(const ElementLayout& el, const ImageView& f, double& x, double& y,
                              double half) const noexcept {
  const double reach = half + 0.5;
  const int col_lo = static_cast<int>(std::ceil(x - reach));
  const int col_hi = static_cast<int>(std::floor(x + reach));
  double s0 = 0;
  double sx = 0;
  double sy = 0;
  for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
    const Span& sp = spans_[s];
    const double fy = soft_edge(half, sp.y - y);
    if (fy <= 0) continue;
    const int xa = std::max(sp.x0, col_lo);
    const int xb = std::min(sp.x1, col_hi + 1);
    const Pixel* row = f.row<Pixel>(sp.y);
    const std::int32_t* ref = ref_q_.data() + sp.ref_offset - sp.x0;
    double r0 = 0;
    double rx = 0;
    for (int px = xa; px < xb; ++px) {
      const std::int32_t w = std::max(q8(row[px]) - ref[px] - floor_q_, 0);
      if (w == 0) continue;
      const double wf = w * soft_edge(half, px - x);
      r0 += wf;
      rx += wf * (px - x);
    }
    s0 += fy * r0;
    sx += fy * rx;
    sy += fy * r0 * (sp.y - y);
  }
  if (!(s0 > 0)) return false;
  const double nx = x + sx / s0;
  const double ny = y + sy / s0;
  if (!std::isfinite(nx) || !std::isfinite(ny)) return false;
  x = nx;
  y = ny;
  return true;
}

// Fills w[k] = exp(-(first + k - c)^2 / (2 s^2)) for k in [0, n) by a recurrence (three exp
// calls in all), with w*u and w*u^2 beside it where u = first + k - c.
static void gaussian_weights(int first, int n, double c, double s, double* w, double* wu,
                             double* wu2) noexcept {
  const double a = 1.0 / (2.0 * s * s);
  double u = first - c;
  double wk = std::exp(-a * u * u);
  double step = std::exp(-a * (2.0 * u + 1.0));
  const double b = std::exp(-2.0 * a);
  for (int k = 0; k < n; ++k, u += 1.0) {
    w[k] = wk;
    if (wu != nullptr) {
      wu[k] = wk * u;
      wu2[k] = wk * u * u;
    }
    wk *= step;
    step *= b;
  }
}

template <typename Pixel>
bool Extractor::gaussian_pass(const ElementLayout& el, const ImageView& f, double& x, double& y,
                              double& sigma) noexcept {
  const double s = sigma;
  const double reach = opt_.gaussian_reach_sigmas * s;
  const Span& first_span = spans_[el.span_begin];
  const Span& last_span = spans_[el.span_end - 1];
  const int row_lo = std::max(first_span.y, static_cast<int>(std::ceil(y - reach)));
  const int row_hi = std::min(last_span.y, static_cast<int>(std::floor(y + reach)));
  const int bbox_w = static_cast<int>(wx_.size());
  const int col_lo = std::max(el.origin_x, static_cast<int>(std::ceil(x - reach)));
  const int col_hi = std::min(el.origin_x + bbox_w - 1, static_cast<int>(std::floor(x + reach)));
  if (row_hi < row_lo || col_hi < col_lo) return false;
  const int ncols = col_hi - col_lo + 1;
  const int nrows = row_hi - row_lo + 1;
  if (ncols > bbox_w || nrows > static_cast<int>(wy_.size())) return false;
  gaussian_weights(col_lo, ncols, x, s, wx_.data(), wxu_.data(), wxu2_.data());
  gaussian_weights(row_lo, nrows, y, s, wy_.data(), nullptr, nullptr);

  double s0 = 0, s1x = 0, s2x = 0, s1y = 0, s2y = 0;
  for (std::uint32_t k = el.span_begin + static_cast<std::uint32_t>(row_lo - first_span.y);
       k < el.span_end; ++k) {
    const Span& sp = spans_[k];
    if (sp.y > row_hi) break;
    const int xa = std::max(sp.x0, col_lo);
    const int xb = std::min(sp.x1, col_hi + 1);
    if (xa >= xb) continue;
    const Pixel* row = f.row<Pixel>(sp.y);
    const std::int32_t* ref = ref_q_.data() + sp.ref_offset - sp.x0;
    const double* wx = wx_.data() - col_lo;
    const double* wxu = wxu_.data() - col_lo;
    const double* wxu2 = wxu2_.data() - col_lo;
    double r0 = 0, r1 = 0, r2 = 0;
    for (int px = xa; px < xb; ++px) {
      // The raw increment, negative values included: the score is linear in the data.
      const auto d = static_cast<double>(q8(row[px]) - ref[px]);
      r0 += d * wx[px];
      r1 += d * wxu[px];
      r2 += d * wxu2[px];
    }
    const double wy = wy_[static_cast<std::size_t>(sp.y - row_lo)];
    const double uy = sp.y - y;
    s0 += wy * r0;
    s1x += wy * r1;
    s2x += wy * r2;
    s1y += wy * uy * r0;
    s2y += wy * uy * uy * r0;
  }
  if (!(s0 > 0)) return false;
  // Newton step on the score sum d (x - c) W(x - c) = 0; where the score is not concave
  // (a spot much wider than the weight) fall back to the weighted-centroid step.
  const double inv_s2 = 1.0 / (s * s);
  const double dfx = s2x * inv_s2 - s0;
  const double dfy = s2y * inv_s2 - s0;
  double step_x = dfx < 0 ? -s1x / dfx : s1x / s0;
  double step_y = dfy < 0 ? -s1y / dfy : s1y / s0;
  if (!(std::abs(step_x) <= s) || !(std::abs(step_y) <= s)) {
    step_x = s1x / s0;
    step_y = s1y / s0;
  }
  x += step_x;
  y += step_y;
  // The weighted second moment is the spot's variance combined with the weight's:
  // 1/m2 = 1/sigma_spot^2 + 1/sigma_weight^2 for a Gaussian spot.
  const double m2 = (s2x + s2y) / (2.0 * s0);
  if (m2 > 0 && m2 < 0.95 * s * s) sigma = 1.0 / std::sqrt(1.0 / m2 - inv_s2);
  return std::isfinite(x) && std::isfinite(y);
}

template <typename Pixel>
void Extractor::measure_all(const ImageView& f, std::uint32_t gap) noexcept {
  const double mm = cal_.mm_per_px;
  for (std::size_t i = 0; i < layout_.size(); ++i) {
    const ElementLayout& el = layout_[i];
    const ElementCalibration& ec = cal_.elements[i];
    ElementState& st = state_[i];
    ElementReading& r = readings_[i];

    const Moments m = first_pass<Pixel>(el, f);
    const double g = static_cast<double>(m.g) / kQ;
    const bool contact = (st.contact ? g >= cal_.contact_off : g >= cal_.contact_on) && m.c0 > 0;

    r = ElementReading{};
    r.id = ec.id;
    r.G = g;
    r.contact = contact;
    if (!contact) {
      st = ElementState{};
      continue;
    }
    double x = el.origin_x + static_cast<double>(m.cx) / static_cast<double>(m.c0);
    double y = el.origin_y + static_cast<double>(m.cy) / static_cast<double>(m.c0);
    if (opt_.estimator == CentroidEstimator::kWindowed) {
      const double half =
          std::sqrt(static_cast<double>(m.above) / std::numbers::pi) + opt_.window_margin_px;
      windowed_pass<Pixel>(el, f, x, y, half);
    } else if (opt_.estimator == CentroidEstimator::kGaussian) {
      // Width of the weight from the spot: for a Gaussian of peak A above a floor f,
      // G = 2 pi sigma^2 (A - f - f ln(A / f)).
      const double peak = m.peak / kQ;
      const double fl = cal_.noise_floor;
      const double shape = fl > 0 ? peak - fl - fl * std::log(std::max(peak / fl, 1.0)) : peak;
      double sigma = shape > 0.05 * peak && shape > 0
                         ? std::sqrt(g / (2 * std::numbers::pi * shape))
                         : ec.radius_px / 4;
      sigma = std::clamp(sigma, 0.6, std::max(0.6, ec.radius_px / 2));
      double gx = x;
      double gy = y;
      const double sigma_before = sigma;
      if (gaussian_pass<Pixel>(el, f, gx, gy, sigma)) {
        // A weight far from the spot's width loses efficiency: once more with the better width.
        if (std::abs(sigma - sigma_before) > 0.25 * sigma_before) {
          sigma = std::clamp(sigma, 0.6, std::max(0.6, ec.radius_px / 2));
          double hx = x;
          double hy = y;
          if (gaussian_pass<Pixel>(el, f, hx, hy, sigma)) {
            gx = hx;
            gy = hy;
          }
        }
        // Keep the estimate only inside the disk; the thresholded centroid always is.
        const double dx = gx - ec.center_px.x;
        const double dy = gy - ec.center_px.y;
        if (dx * dx + dy * dy <= ec.radius_px * ec.radius_px) {
          x = gx;
          y = gy;
        }
      }
    }
    r.x_px = x;
    r.y_px = y;
    r.ux_mm = (x - ec.zero_px.x) * mm;
    r.uy_mm = (y - ec.zero_px.y) * mm;
    r.fz = cal_.normal_curve(g);
    r.fx = cal_.shear_curve.odd(r.ux_mm);
    r.fy = cal_.shear_curve.odd(r.uy_mm);
    if (st.contact && gap > 0) {
      r.has_displacement = true;
      r.dx_mm = (x - st.x_px) * mm / gap;
      r.dy_mm = (y - st.y_px) * mm / gap;
    }
    st.contact = true;
    st.x_px = x;
    st.y_px = y;
  }
}

MeasureStatus Extractor::measure(const ImageView& f, FrameInfo info) noexcept {
  if (!has_reference_) return MeasureStatus::kNoReference;
  if (!geometry_matches(f)) return MeasureStatus::kWrongSize;
  if (bit_depth(f.format) != cal_.bit_depth) return MeasureStatus::kWrongFormat;

  std::uint32_t gap = 0;
  if (has_previous_ && info.sequence > previous_sequence_ &&
      info.sequence - previous_sequence_ <= opt_.max_gap_frames) {
    gap = static_cast<std::uint32_t>(info.sequence - previous_sequence_);
  }
  if (f.format == PixelFormat::kMono8) {
    measure_all<std::uint8_t>(f, gap);
  } else {
    measure_all<std::uint16_t>(f, gap);
  }
  has_previous_ = true;
  previous_sequence_ = info.sequence;
  return MeasureStatus::kOk;
}

}  // namespace tactile
