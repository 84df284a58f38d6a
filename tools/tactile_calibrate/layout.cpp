// The layout step: where the sensing elements are, from frames of a light press.
//
// 1. The increment that shows the spots: each frame minus the mean of the no-load references,
//    or (without references) the mean of the frames minus a background estimated from it.
// 2. Spots: connected areas of the smoothed increment above 3 noise sigmas holding a pixel
//    above `detect_sigmas`, at least `min_area` pixels, whose summed increment reaches
//    contact.off; detections in several frames closer than `merge_px` are one element.
// 3. Refusals: a count other than --expect, overlapping disks, a disk leaving the image.
// 4. The positions again with the real measurement core (disks centred on the first estimate,
//    then once more on the result), averaged over the frames where the element is in contact:
//    zero_px is the centroid the core will measure under pure normal load.
// 5. Order (rings by radius then azimuth, or rows) and normals (dome model or [0, 0, 1]).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "calibrate.hpp"

namespace tactile::calibrate {
namespace {

constexpr double kPi = std::numbers::pi;

struct Plane {
  int width = 0;
  int height = 0;
  std::vector<double> v;
  double& at(int x, int y) {
    return v[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
             static_cast<std::size_t>(x)];
  }
  double at(int x, int y) const {
    return v[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
             static_cast<std::size_t>(x)];
  }
};

Plane to_plane(const Image& img) {
  Plane p{img.width(), img.height(), {}};
  p.v.resize(static_cast<std::size_t>(img.width()) * static_cast<std::size_t>(img.height()));
  const ImageView view = img.view();
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      p.at(x, y) = static_cast<double>(view.at(x, y));
  return p;
}

Plane mean_of(const std::vector<Image>& images) {
  Plane m = to_plane(images.front());
  for (std::size_t i = 1; i < images.size(); ++i) {
    const ImageView view = images[i].view();
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x)
        m.at(x, y) += static_cast<double>(view.at(x, y));
  }
  for (double& v : m.v)
    v /= static_cast<double>(images.size());
  return m;
}

Plane difference(const Plane& a, const Plane& b) {
  Plane d = a;
  for (std::size_t i = 0; i < d.v.size(); ++i)
    d.v[i] -= b.v[i];
  return d;
}

// Which pixels change at all across the frames and references (1) and which hold the same value
// in every one (0): a part of the image the camera does not see (a mask, a dead region), or a
// simulator that draws fresh noise only where it is measured. Such pixels carry no noise and
// would make the noise of an increment look far smaller than it is (docs/calibration.md). With
// fewer than three images any pixel may repeat by chance: all count as changing.
using LiveMask = std::vector<std::uint8_t>;
LiveMask live_pixels(const LayoutInput& in) {
  const Image& first = in.frames.front();
  LiveMask live(static_cast<std::size_t>(first.width()) * static_cast<std::size_t>(first.height()),
                1);
  if (in.frames.size() + in.references.size() < 3) return live;
  std::fill(live.begin(), live.end(), 0);
  const ImageView base = first.view();
  for (const auto* list : {&in.frames, &in.references}) {
    for (const Image& img : *list) {
      const ImageView v = img.view();
      std::size_t i = 0;
      for (int y = 0; y < first.height(); ++y)
        for (int x = 0; x < first.width(); ++x, ++i)
          live[i] = live[i] | static_cast<std::uint8_t>(v.at(x, y) != base.at(x, y));
    }
  }
  // An image with no pixel changing at all: nothing to learn from the mask.
  if (std::find(live.begin(), live.end(), std::uint8_t{1}) == live.end())
    std::fill(live.begin(), live.end(), 1);
  return live;
}

// Mean and standard deviation of the values where `live` is set, ignoring those more than 4
// sigmas from the mean (spots are the outliers): the noise of an increment image.
std::pair<double, double> clipped_stats(const std::vector<double>& v, const LiveMask& live) {
  double mean = 0;
  double sd = INFINITY;
  for (int iter = 0; iter < 6; ++iter) {
    double s = 0;
    double s2 = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const double x = v[i];
      if (!live[i] || std::abs(x - mean) > 4 * sd) continue;
      s += x;
      s2 += x * x;
      ++n;
    }
    if (n < 2) break;
    const double m = s / static_cast<double>(n);
    mean = m;
    sd = std::sqrt(std::max(s2 / static_cast<double>(n) - m * m, 1e-12));
  }
  return {mean, std::isfinite(sd) ? sd : 0.0};
}

// The background of a light-press image without a reference: on a grid every 16 pixels, the
// mean of the middle half of the values within 24 pixels (spots fall in the top quarter and are
// dropped), interpolated bilinearly. Vignetting is smooth: the grid follows it closely.
Plane estimate_background(const Plane& img) {
  constexpr int kCell = 16;
  constexpr int kReach = 24;
  const int gw = (img.width - 1) / kCell + 2;
  const int gh = (img.height - 1) / kCell + 2;
  std::vector<double> grid(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh));
  std::vector<double> values;
  for (int gy = 0; gy < gh; ++gy) {
    for (int gx = 0; gx < gw; ++gx) {
      const int cx = std::min(gx * kCell, img.width - 1);
      const int cy = std::min(gy * kCell, img.height - 1);
      values.clear();
      for (int y = std::max(0, cy - kReach); y <= std::min(img.height - 1, cy + kReach); ++y)
        for (int x = std::max(0, cx - kReach); x <= std::min(img.width - 1, cx + kReach); ++x)
          values.push_back(img.at(x, y));
      std::sort(values.begin(), values.end());
      const std::size_t lo = values.size() / 4;
      const std::size_t hi = std::max(lo + 1, values.size() * 3 / 4);
      double s = 0;
      for (std::size_t i = lo; i < hi; ++i)
        s += values[i];
      grid[static_cast<std::size_t>(gy) * static_cast<std::size_t>(gw) +
           static_cast<std::size_t>(gx)] = s / static_cast<double>(hi - lo);
    }
  }
  Plane bg{img.width, img.height, std::vector<double>(img.v.size())};
  for (int y = 0; y < img.height; ++y) {
    const int gy = std::min(y / kCell, gh - 2);
    const double fy = (y - gy * kCell) / static_cast<double>(kCell);
    for (int x = 0; x < img.width; ++x) {
      const int gx = std::min(x / kCell, gw - 2);
      const double fx = (x - gx * kCell) / static_cast<double>(kCell);
      const auto g = [&](int i, int j) {
        return grid[static_cast<std::size_t>(j) * static_cast<std::size_t>(gw) +
                    static_cast<std::size_t>(i)];
      };
      bg.at(x, y) = (1 - fy) * ((1 - fx) * g(gx, gy) + fx * g(gx + 1, gy)) +
                    fy * ((1 - fx) * g(gx, gy + 1) + fx * g(gx + 1, gy + 1));
    }
  }
  return bg;
}

// Gaussian smoothing with sigma 1 pixel (separable, edges clamped).
Plane smooth(const Plane& in) {
  constexpr int kR = 3;
  double k[2 * kR + 1];
  double sum = 0;
  for (int i = -kR; i <= kR; ++i) {
    k[i + kR] = std::exp(-0.5 * i * i);
    sum += k[i + kR];
  }
  for (double& v : k)
    v /= sum;
  Plane tmp = in;
  Plane out = in;
  for (int y = 0; y < in.height; ++y) {
    for (int x = 0; x < in.width; ++x) {
      double s = 0;
      for (int i = -kR; i <= kR; ++i)
        s += k[i + kR] * in.at(std::clamp(x + i, 0, in.width - 1), y);
      tmp.at(x, y) = s;
    }
  }
  for (int y = 0; y < in.height; ++y) {
    for (int x = 0; x < in.width; ++x) {
      double s = 0;
      for (int i = -kR; i <= kR; ++i)
        s += k[i + kR] * tmp.at(x, std::clamp(y + i, 0, in.height - 1));
      out.at(x, y) = s;
    }
  }
  return out;
}

struct Detection {
  Vec2 position;
  double strength = 0;  // summed positive increment over the spot's area
};

std::vector<Detection> detect(const Plane& inc, const LiveMask& live, const LayoutOptions& o,
                              double min_strength) {
  const Plane s = smooth(inc);
  const auto [mean, sd] = clipped_stats(s.v, live);
  const double low = mean + 3 * std::max(sd, 1e-9);
  const double high = mean + o.detect_sigmas * std::max(sd, 1e-9);
  std::vector<std::uint8_t> seen(s.v.size(), 0);
  std::vector<Detection> out;
  std::vector<std::pair<int, int>> stack;
  std::vector<std::pair<int, int>> area;
  for (int y0 = 0; y0 < s.height; ++y0) {
    for (int x0 = 0; x0 < s.width; ++x0) {
      const std::size_t i0 = static_cast<std::size_t>(y0) * static_cast<std::size_t>(s.width) +
                             static_cast<std::size_t>(x0);
      if (seen[i0] || s.v[i0] <= low) continue;
      // Flood fill of the connected area above `low` (8-connectivity).
      stack.assign(1, {x0, y0});
      seen[i0] = 1;
      area.clear();
      bool seeded = false;
      while (!stack.empty()) {
        const auto [x, y] = stack.back();
        stack.pop_back();
        area.emplace_back(x, y);
        seeded = seeded || s.at(x, y) > high;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx;
            const int ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= s.width || ny >= s.height) continue;
            const std::size_t j = static_cast<std::size_t>(ny) * static_cast<std::size_t>(s.width) +
                                  static_cast<std::size_t>(nx);
            if (seen[j] || s.v[j] <= low) continue;
            seen[j] = 1;
            stack.emplace_back(nx, ny);
          }
        }
      }
      if (!seeded || static_cast<int>(area.size()) < o.min_area) continue;
      double w = 0;
      double wx = 0;
      double wy = 0;
      for (const auto& [x, y] : area) {
        const double v = std::max(inc.at(x, y), 0.0);
        w += v;
        wx += v * x;
        wy += v * y;
      }
      if (w < min_strength || !(w > 0)) continue;
      out.push_back({{wx / w, wy / w}, w});
    }
  }
  return out;
}

struct Cluster {
  Vec2 sum;
  std::size_t n = 0;
  double strength = 0;
  Vec2 mean() const { return {sum.x / static_cast<double>(n), sum.y / static_cast<double>(n)}; }
};

void add_detections(std::vector<Cluster>& clusters, const std::vector<Detection>& found,
                    double merge_px) {
  for (const Detection& d : found) {
    Cluster* best = nullptr;
    double best_d = merge_px;
    for (Cluster& c : clusters) {
      const double dist = norm(c.mean() - d.position);
      if (dist < best_d) {
        best_d = dist;
        best = &c;
      }
    }
    if (best == nullptr) {
      clusters.push_back({d.position, 1, d.strength});
    } else {
      best->sum = best->sum + d.position;
      best->n += 1;
      best->strength = std::max(best->strength, d.strength);
    }
  }
}

std::string at(Vec2 p) {
  return fmt::format("({:.1f}, {:.1f})", p.x, p.y);
}

Image to_preview(const Plane& inc) {
  std::vector<double> pos;
  for (double v : inc.v)
    if (v > 0) pos.push_back(v);
  double top = 1;
  if (!pos.empty()) {
    const std::size_t k = std::min(pos.size() - 1, pos.size() * 999 / 1000);
    std::nth_element(pos.begin(), pos.begin() + static_cast<std::ptrdiff_t>(k), pos.end());
    top = std::max(pos[k], 1e-9);
  }
  Image out(inc.width, inc.height, PixelFormat::kMono8);
  for (int y = 0; y < inc.height; ++y)
    for (int x = 0; x < inc.width; ++x)
      out.set(x, y, static_cast<std::uint32_t>(std::clamp(200.0 * inc.at(x, y) / top, 0.0, 200.0)));
  return out;
}

// Groups sorted values where consecutive ones differ by more than `gap`.
std::vector<std::vector<std::size_t>> group_by_gap(const std::vector<double>& key, double gap) {
  std::vector<std::size_t> idx(key.size());
  for (std::size_t i = 0; i < idx.size(); ++i)
    idx[i] = i;
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t k = 0; k < idx.size(); ++k) {
    if (k == 0 || key[idx[k]] - key[idx[k - 1]] > gap) groups.emplace_back();
    groups.back().push_back(idx[k]);
  }
  return groups;
}

std::string join(const std::vector<int>& v) {
  return fmt::format("{}", fmt::join(v, ", "));
}

}  // namespace

PiecewiseLinear placeholder_normal_curve(int bit_depth) {
  const double scale = bit_depth == 16 ? 257.0 : 1.0;
  return PiecewiseLinear({0, 2000 * scale, 8000 * scale, 20000 * scale}, {0, 0.2, 1.0, 3.0});
}

PiecewiseLinear placeholder_shear_curve() {
  return PiecewiseLinear({0, 0.02, 0.08}, {0, 0.05, 0.4});
}

namespace {

void check_options(const LayoutOptions& o) {
  if (o.sensor_id.empty()) throw std::invalid_argument("--sensor-id must not be empty");
  if (!(o.mm_per_px > 0) || !std::isfinite(o.mm_per_px))
    throw std::invalid_argument("--mm-per-px must be a positive number");
  if (!(o.radius_px >= 0) || o.radius_px > kMaxRadiusPx)
    throw std::invalid_argument("--radius must be 0 (automatic) to 1024 pixels");
  if (!(o.detect_sigmas > 3)) throw std::invalid_argument("--detect-sigmas must be above 3");
  if (o.min_area < 1) throw std::invalid_argument("--min-area must be at least 1");
  if (!(o.merge_px > 0)) throw std::invalid_argument("--merge-px must be positive");
}

// Every frame and reference has the first frame's size and format.
void check_sizes(const LayoutInput& in) {
  const Image& first = in.frames.front();
  const auto describe = [](const Image& i) {
    return fmt::format("{}x{} {}-bit", i.width(), i.height(), bit_depth(i.format()));
  };
  for (const auto* list : {&in.frames, &in.references}) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      const Image& img = (*list)[i];
      if (img.width() != first.width() || img.height() != first.height() ||
          img.format() != first.format()) {
        throw std::runtime_error(fmt::format("{} {} is {}, the first frame is {}",
                                             list == &in.frames ? "frame" : "reference", i + 1,
                                             describe(img), describe(first)));
      }
    }
  }
}

// Counts frames for the progress report: each frame is looked at three times (spots, and two
// passes of the measurement core).
class FrameProgress {
 public:
  FrameProgress(const Progress& progress, std::size_t frames)
      : progress_(progress), total_(frames * 3) {}
  void advance(std::size_t frames = 1) {
    done_ += frames;
    if (progress_) progress_(done_, total_, "frames");
  }

 private:
  const Progress& progress_;
  std::size_t total_;
  std::size_t done_ = 0;
};

// What the increment is taken against: the mean of the no-load references, or (without them) a
// background estimated from the mean of the frames.
Plane no_load_plane(const LayoutInput& in) {
  if (!in.references.empty()) return mean_of(in.references);
  return estimate_background(mean_of(in.frames));
}

// One frame's noise: from two frames of the same kind when there are two, else from a frame
// against the reference (spots are clipped as outliers).
double frame_noise(const LayoutInput& in, const Plane& reference, const LiveMask& live) {
  Plane d;
  double factor = std::sqrt(0.5);
  if (in.references.size() >= 2) {
    d = difference(to_plane(in.references[0]), to_plane(in.references[1]));
  } else if (!in.references.empty()) {
    d = difference(to_plane(in.frames[0]), to_plane(in.references[0]));
  } else if (in.frames.size() >= 2) {
    d = difference(to_plane(in.frames[0]), to_plane(in.frames[1]));
  } else {
    d = difference(to_plane(in.frames[0]), reference);
    factor = 1.0;
  }
  return factor * clipped_stats(d.v, live).second;
}

// The calibration without elements: thresholds scaled to the noise unless given.
Calibration thresholds_for(const Image& first, const LayoutOptions& o, double noise_sigma) {
  const int depth = bit_depth(first.format());
  const double scale = depth == 16 ? 257.0 : 1.0;
  const double sigma8 = noise_sigma / scale;
  const double noise_scale = std::max(1.0, sigma8 / 2.0);
  Calibration cal;
  cal.sensor_id = o.sensor_id;
  cal.width = first.width();
  cal.height = first.height();
  cal.bit_depth = depth;
  cal.mm_per_px = o.mm_per_px;
  cal.noise_floor = o.noise_floor.value_or(scale * std::max(4.0, 3.0 * sigma8));
  cal.contact_on = o.contact_on.value_or(scale * 400.0 * noise_scale);
  cal.contact_off = o.contact_off.value_or(std::min(scale * 250.0 * noise_scale, cal.contact_on));
  cal.normal_curve = placeholder_normal_curve(depth);
  cal.shear_curve = placeholder_shear_curve();
  return cal;
}

// Spots: each frame's increment (or, without references, the mean frame's) searched for spots;
// detections close together are one element. `preview` gets the largest increment seen.
std::vector<Cluster> find_spots(const LayoutInput& in, const LiveMask& live, const LayoutOptions& o,
                                const Plane& reference, double min_strength,
                                FrameProgress& progress, Plane& preview) {
  std::vector<Cluster> clusters;
  if (in.references.empty()) {
    preview = difference(mean_of(in.frames), reference);
    add_detections(clusters, detect(preview, live, o, min_strength), o.merge_px);
    progress.advance(in.frames.size());
    return clusters;
  }
  const Image& first = in.frames.front();
  preview = Plane{first.width(), first.height(), std::vector<double>(reference.v.size())};
  for (const Image& f : in.frames) {
    const Plane inc = difference(to_plane(f), reference);
    for (std::size_t i = 0; i < inc.v.size(); ++i)
      preview.v[i] = std::max(preview.v[i], inc.v[i]);
    add_detections(clusters, detect(inc, live, o, min_strength), o.merge_px);
    progress.advance();
  }
  return clusters;
}

// Refusal: a count other than --expect, or none at all.
void check_count(const std::vector<Cluster>& clusters, const LayoutOptions& o) {
  if (o.expect != 0 && clusters.size() != o.expect) {
    std::string detail;
    if (clusters.size() > o.expect) {
      std::vector<const Cluster*> weakest;
      for (const Cluster& c : clusters)
        weakest.push_back(&c);
      std::sort(weakest.begin(), weakest.end(),
                [](const Cluster* a, const Cluster* b) { return a->strength < b->strength; });
      detail = "; the weakest at";
      for (std::size_t i = 0; i < std::min<std::size_t>(3, clusters.size() - o.expect); ++i)
        detail += fmt::format(" {} (summed increment {:.0f})", at(weakest[i]->mean()),
                              weakest[i]->strength);
      detail += ": dust, a hot pixel or a glowing element? (--detect-sigmas, --min-area)";
    } else {
      detail =
          ": press so that every element shows a spot (each in at least one frame), or check "
          "--detect-sigmas and the focus; --marks FILE.pgm shows what was found";
    }
    throw std::runtime_error(fmt::format("found {} elements, expected {} (--expect){}",
                                         clusters.size(), o.expect, detail));
  }
  if (clusters.empty()) {
    throw std::runtime_error(
        "found no elements: no spot stands out of the noise (is the sensor pressed, lit, in "
        "focus?)");
  }
}

// The disks' radius: --radius, or 0.45 of the closest spots' distance; refused where disks
// would overlap or leave the image.
double disk_radius(const std::vector<Cluster>& clusters, const LayoutOptions& o,
                   const Calibration& cal) {
  double min_dist = INFINITY;
  std::size_t pa = 0;
  std::size_t pb = 0;
  for (std::size_t i = 0; i < clusters.size(); ++i) {
    for (std::size_t j = i + 1; j < clusters.size(); ++j) {
      const double d = norm(clusters[i].mean() - clusters[j].mean());
      if (d < min_dist) {
        min_dist = d;
        pa = i;
        pb = j;
      }
    }
  }
  double radius = o.radius_px;
  if (radius == 0) {
    radius = std::isfinite(min_dist) ? std::floor(2.0 * 0.45 * min_dist) / 2.0 : 14.0;
    if (radius < 1.0) {
      throw std::runtime_error(
          fmt::format("the spots at {} and {} are only {:.1f} px apart: too close for a disk each",
                      at(clusters[pa].mean()), at(clusters[pb].mean()), min_dist));
    }
  } else if (std::isfinite(min_dist) && min_dist < 2 * radius) {
    throw std::runtime_error(fmt::format(
        "the disks of the elements at {} and {} overlap: their spots are {:.2f} px apart, less "
        "than twice the radius {} px: give --radius {:.1f} or less",
        at(clusters[pa].mean()), at(clusters[pb].mean()), min_dist, radius,
        std::floor(10.0 * (min_dist / 2.0 - 0.05)) / 10.0));
  }
  for (const Cluster& c : clusters) {
    const Vec2 p = c.mean();
    if (p.x - radius < -0.5 || p.y - radius < -0.5 || p.x + radius > cal.width - 0.5 ||
        p.y + radius > cal.height - 0.5) {
      throw std::runtime_error(fmt::format(
          "the disk of the element at {} with radius {} px leaves the {}x{} image: give a "
          "smaller --radius, or move the sensor in the image",
          at(p), radius, cal.width, cal.height));
    }
  }
  return radius;
}

// The measurement core on disks of `radius` centred on `pos`, its reference taken from the
// no-load references (or the estimated background).
Extractor core_at(const std::vector<Vec2>& pos, double radius, const Calibration& cal,
                  const LayoutInput& in, const LayoutOptions& o, const Plane& reference) {
  const bool with_reference = !in.references.empty();
  ExtractorOptions xo;
  xo.estimator = o.estimator;
  xo.reference_spot_check = false;
  xo.reference_frames = with_reference ? static_cast<int>(in.references.size()) : 1;
  Calibration trial = cal;
  trial.elements.clear();
  for (std::size_t i = 0; i < pos.size(); ++i) {
    ElementCalibration e;
    e.id = static_cast<std::uint32_t>(i);
    e.center_px = pos[i];
    e.radius_px = radius;
    e.zero_px = pos[i];
    trial.elements.push_back(e);
  }
  Extractor ex(trial, xo);
  ReferenceResult rr;
  if (with_reference) {
    for (const Image& r : in.references)
      rr = ex.add_reference_frame(r.view());
  } else {
    const Image& first = in.frames.front();
    Image bg(cal.width, cal.height, first.format());
    const double top = bit_depth(first.format()) == 16 ? 65535.0 : 255.0;
    for (int y = 0; y < cal.height; ++y)
      for (int x = 0; x < cal.width; ++x)
        bg.set(x, y,
               static_cast<std::uint32_t>(std::clamp(std::round(reference.at(x, y)), 0.0, top)));
    rr = ex.add_reference_frame(bg.view());
  }
  if (!ex.has_reference()) {
    throw std::runtime_error(std::string("the no-load references were refused: ") +
                             to_string(rr.status) +
                             " (something moved or touched the sensor while they were taken)");
  }
  return ex;
}

// Sums over the frames where each element is in contact.
struct ContactSums {
  explicit ContactSums(std::size_t elements)
      : sum(elements), sum2(elements), g(elements, 0.0), n(elements, 0) {}
  std::vector<Vec2> sum;
  std::vector<Vec2> sum2;
  std::vector<double> g;
  std::vector<std::size_t> n;
};

ContactSums measure_frames(Extractor& ex, const std::vector<Image>& frames,
                           FrameProgress& progress) {
  ContactSums t(ex.readings().size());
  const Image blank = ex.reference_image();
  std::uint64_t seq = 0;
  for (const Image& f : frames) {
    // The blank frame ends every contact, so each frame is measured on its own.
    ex.measure(blank.view(), {seq, 0});
    ex.measure(f.view(), {seq + 10, 0});
    seq += 20;
    const auto readings = ex.readings();
    for (std::size_t i = 0; i < readings.size(); ++i) {
      if (!readings[i].contact) continue;
      t.sum[i] = t.sum[i] + Vec2{readings[i].x_px, readings[i].y_px};
      t.sum2[i] = t.sum2[i] +
                  Vec2{readings[i].x_px * readings[i].x_px, readings[i].y_px * readings[i].y_px};
      t.g[i] += readings[i].G;
      t.n[i] += 1;
    }
    progress.advance();
  }
  return t;
}

// The positions again with the real measurement core (disks centred on the first estimate, then
// once more on the result), averaged over the frames where the element is in contact. Updates
// `pos` and fills the elements' position, frames, G and spread.
std::vector<FoundElement> measure_positions(std::vector<Vec2>& pos, double radius,
                                            const Calibration& cal, const LayoutInput& in,
                                            const LayoutOptions& o, const Plane& reference,
                                            FrameProgress& progress) {
  std::vector<FoundElement> found(pos.size());
  for (int pass = 0; pass < 2; ++pass) {
    Extractor ex = core_at(pos, radius, cal, in, o, reference);
    const ContactSums t = measure_frames(ex, in.frames, progress);
    for (std::size_t i = 0; i < pos.size(); ++i) {
      if (t.n[i] == 0) {
        throw std::runtime_error(fmt::format(
            "the element at {} is never in contact (G below contact.on {:.0f} in every frame): "
            "press harder, or give a lower --contact-on",
            at(pos[i]), cal.contact_on));
      }
      const double k = static_cast<double>(t.n[i]);
      pos[i] = {t.sum[i].x / k, t.sum[i].y / k};
      found[i].position = pos[i];
      found[i].frames = t.n[i];
      found[i].G = t.g[i] / k;
      const double vx = std::max(t.sum2[i].x / k - pos[i].x * pos[i].x, 0.0);
      const double vy = std::max(t.sum2[i].y / k - pos[i].y * pos[i].y, 0.0);
      found[i].spread_px = t.n[i] > 1 ? std::sqrt((vx + vy) / (k - 1)) : 0.0;
    }
  }
  return found;
}

// Elements in calibration order: groups (rings or rows) in order, each sorted; azimuth in
// radians (rings only).
struct Order {
  std::vector<std::vector<std::size_t>> groups;
  std::vector<double> azimuth;
};

// Rings by radius from the centre, then azimuth. Sets each element's radius_from_center.
Order order_rings(const std::vector<Vec2>& pos, Vec2 center, double gap, const LayoutOptions& o,
                  std::vector<FoundElement>& found) {
  Order order;
  order.azimuth.assign(pos.size(), 0.0);
  std::vector<double>& azimuth = order.azimuth;
  std::vector<double> rho(pos.size());
  for (std::size_t i = 0; i < pos.size(); ++i) {
    const Vec2 d = pos[i] - center;
    rho[i] = norm(d);
    found[i].radius_from_center = rho[i];
    const double phi = std::atan2(d.y, d.x);
    azimuth[i] = (o.mirror ? -phi : phi) + o.azimuth_offset_deg * kPi / 180.0;
  }
  order.groups = group_by_gap(rho, gap);
  for (auto& ring : order.groups) {
    // Azimuth in [-q, 2 pi - q) with q a quarter of the ring's step: an element drawn at 0
    // degrees stays first whatever the noise.
    const double q = kPi / (2.0 * static_cast<double>(ring.size()));
    const auto key = [&](std::size_t i) {
      double a = std::fmod(azimuth[i] + q, 2 * kPi);
      if (a < 0) a += 2 * kPi;
      return a - q;
    };
    for (std::size_t i : ring)
      azimuth[i] = key(i);
    std::sort(ring.begin(), ring.end(),
              [&](std::size_t a, std::size_t b) { return azimuth[a] < azimuth[b]; });
  }
  return order;
}

// Rows by y, then x.
Order order_rows(const std::vector<Vec2>& pos, double gap) {
  Order order;
  order.azimuth.assign(pos.size(), 0.0);
  std::vector<double> ys(pos.size());
  for (std::size_t i = 0; i < pos.size(); ++i)
    ys[i] = pos[i].y;
  order.groups = group_by_gap(ys, gap);
  for (auto& row : order.groups)
    std::sort(row.begin(), row.end(),
              [&](std::size_t a, std::size_t b) { return pos[a].x < pos[b].x; });
  return order;
}

// Refusals: groups other than --rings, --ring-polar-deg that does not fit the rings.
void check_groups(const LayoutResult& result, const LayoutOptions& o, std::size_t groups,
                  double gap) {
  const char* group_name = o.order == ElementOrder::kRings ? "rings" : "rows";
  if (!o.ring_counts.empty() && o.ring_counts != result.group_counts) {
    throw std::runtime_error(fmt::format(
        "the {} found hold {} elements, --rings says {} (a new {} starts where positions differ "
        "by more than {} px: --ring-gap; the layout centre is {}: --center)",
        group_name, join(result.group_counts), join(o.ring_counts),
        o.order == ElementOrder::kRings ? "ring" : "row", gap, at(result.center)));
  }
  if (!result.dome_normals) return;
  if (o.order != ElementOrder::kRings)
    throw std::invalid_argument("--ring-polar-deg needs --order rings");
  if (o.ring_polar_deg.size() != groups) {
    throw std::runtime_error(
        fmt::format("--ring-polar-deg gives {} rings, the layout has {} (holding {} elements)",
                    o.ring_polar_deg.size(), groups, join(result.group_counts)));
  }
}

// The elements in order into the calibration and the result, with ids, rings and normals (the
// dome model, or [0, 0, 1]).
void add_elements(const Order& order, const std::vector<FoundElement>& found, double radius,
                  const LayoutOptions& o, Calibration& cal, LayoutResult& result) {
  std::uint32_t id = 0;
  for (std::size_t gi = 0; gi < order.groups.size(); ++gi) {
    for (std::size_t i : order.groups[gi]) {
      const double azimuth = order.azimuth[i];
      FoundElement f = found[i];
      f.id = id++;
      f.ring = static_cast<int>(gi);
      f.azimuth_deg = o.order == ElementOrder::kRings ? azimuth * 180.0 / kPi : 0.0;
      ElementCalibration e;
      e.id = f.id;
      e.center_px = f.position;
      e.radius_px = radius;
      e.zero_px = f.position;
      if (result.dome_normals) {
        const double t = o.ring_polar_deg[gi] * kPi / 180.0;
        e.normal = {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)};
      }
      cal.elements.push_back(e);
      result.elements.push_back(f);
    }
  }
}

Vec2 mean_position(const std::vector<Vec2>& pos) {
  Vec2 center{0, 0};
  for (const Vec2& p : pos)
    center = center + p;
  return (1.0 / static_cast<double>(pos.size())) * center;
}

}  // namespace

LayoutResult find_layout(const LayoutInput& in, const LayoutOptions& o, const Progress& progress) {
  if (in.frames.empty()) throw std::invalid_argument("no frames given");
  check_options(o);
  check_sizes(in);
  FrameProgress frames(progress, in.frames.size());

  LayoutResult result;
  const Plane reference = no_load_plane(in);
  const LiveMask live = live_pixels(in);
  result.noise_sigma = frame_noise(in, reference, live);
  Calibration cal = thresholds_for(in.frames.front(), o, result.noise_sigma);

  Plane preview;
  const std::vector<Cluster> clusters =
      find_spots(in, live, o, reference, cal.contact_off, frames, preview);
  result.increment_preview = to_preview(preview);
  check_count(clusters, o);
  const double radius = disk_radius(clusters, o, cal);

  std::vector<Vec2> pos;
  for (const Cluster& c : clusters)
    pos.push_back(c.mean());
  std::vector<FoundElement> found = measure_positions(pos, radius, cal, in, o, reference, frames);

  result.center = o.center ? *o.center : mean_position(pos);
  const double gap = o.ring_gap_px > 0 ? o.ring_gap_px : radius;
  const Order order = o.order == ElementOrder::kRings
                          ? order_rings(pos, result.center, gap, o, found)
                          : order_rows(pos, gap);
  for (const auto& group : order.groups)
    result.group_counts.push_back(static_cast<int>(group.size()));
  result.dome_normals = !o.ring_polar_deg.empty();
  check_groups(result, o, order.groups.size(), gap);
  add_elements(order, found, radius, o, cal, result);
  validate(cal);
  result.calibration = std::move(cal);
  return result;
}

Image mark_layout(const LayoutResult& result) {
  Image out = result.increment_preview;
  const auto plot = [&out](double x, double y) {
    const int ix = static_cast<int>(std::lround(x));
    const int iy = static_cast<int>(std::lround(y));
    if (ix >= 0 && iy >= 0 && ix < out.width() && iy < out.height()) out.set(ix, iy, 255);
  };
  for (const ElementCalibration& e : result.calibration.elements) {
    const int steps = std::max(16, static_cast<int>(8 * e.radius_px));
    for (int k = 0; k < steps; ++k) {
      const double a = 2 * kPi * k / steps;
      plot(e.center_px.x + e.radius_px * std::cos(a), e.center_px.y + e.radius_px * std::sin(a));
    }
    for (int d = -3; d <= 3; ++d) {
      plot(e.zero_px.x + d, e.zero_px.y);
      plot(e.zero_px.x, e.zero_px.y + d);
    }
  }
  return out;
}

}  // namespace tactile::calibrate
