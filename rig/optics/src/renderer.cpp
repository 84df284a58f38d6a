#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>

#include "tactile/detail/multiversion.hpp"
#include "tactile/rig/optics.hpp"

namespace tactile::rig {
namespace {

constexpr std::size_t kPoolSize = std::size_t{1} << 20;
constexpr std::array<int, 4> kRingCount{1, 8, 16, 16};

// E[max(X - f, 0)] for X ~ N(mu, sigma^2).
double partial_expectation(double mu, double f, double sigma) {
  const double d = mu - f;
  if (sigma <= 0) return std::max(d, 0.0);
  const double z = d / sigma;
  const double cdf = 0.5 * std::erfc(-z / std::numbers::sqrt2);
  const double pdf = std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi);
  return d * cdf + sigma * pdf;
}

// A pixel's noise sigma at `value`: the read noise with, for gain > 0, the shot noise of variance
// scale value / gain (Renderer::pixel_sigma; spot_row inlines it).
[[gnu::always_inline]] inline double noise_sigma_at(double read, double scale, double gain,
                                                    double value) noexcept {
  const double shot = gain > 0 ? scale * std::max(value, 0.0) / gain : 0.0;
  return std::sqrt(read * read + shot);
}

// One disk's pixels with their noise: value + sigma z, clamped to the sensor's range [0, top] and
// rounded half up (values are never negative here). Rows y0..y1 of a box w wide, each written
// over its span's columns only; the noise samples z keep the whole box's offsets, so a disk
// pixel's noise does not depend on which pixels around it are drawn. Without shot noise every
// pixel's sigma is the read noise's: `sigma` is then that one value (one load less per pixel, the
// same numbers).
template <bool kOneSigma, typename Pixel>
[[gnu::always_inline]] inline void noisy_rows(const float* value, const float* sigma,
                                              const float* z, const Renderer::Span* spans, int rows,
                                              std::size_t w, Pixel* row, std::size_t stride,
                                              float top) noexcept {
  const float one_sigma = *sigma;
  for (int r = 0; r < rows; ++r, ++spans) {
    // Bounds in locals: the pixel stores may alias anything (8-bit pixels), so a bound read
    // through `spans` would be reloaded every pixel and the loop left unvectorised.
    const auto x_end = static_cast<std::size_t>(spans->x1);
    for (auto x = static_cast<std::size_t>(spans->x0); x < x_end; ++x) {
      const float s = kOneSigma ? one_sigma : sigma[x];
      const float v = std::clamp(value[x] + s * z[x], 0.0F, top);
      row[x] = static_cast<Pixel>(v + 0.5F);
    }
    value += w;
    if constexpr (!kOneSigma) sigma += w;
    z += w;
    row += stride;
  }
}

// noisy_rows for each pixel type, compiled for AVX2 and the baseline.
template <typename Pixel>
TACTILE_CLONES_SAME_BITS void noisy_pixels(const float* value, const float* sigma, bool one_sigma,
                                           const float* z, const Renderer::Span* spans, int rows,
                                           std::size_t w, Pixel* row, std::size_t stride,
                                           float top) noexcept {
  if (one_sigma) {
    noisy_rows<true>(value, sigma, z, spans, rows, w, row, stride, top);
  } else {
    noisy_rows<false>(value, sigma, z, spans, rows, w, row, stride, top);
  }
}

// A Gaussian spot's row over its span [j0, j1): value = background + ey column_exp, and its noise
// sigma. The loop is written once per side of `gain > 0`, so that each, knowing it, vectorises.
TACTILE_CLONES_SAME_BITS
void spot_row(const float* bg, const double* column_exp, double ey, double read, double scale,
              double gain, std::size_t j0, std::size_t j1, float* value, float* sigma) noexcept {
  const auto row = [&](double g) {
    for (std::size_t u = j0; u < j1; ++u) {
      const double v = static_cast<double>(bg[u]) + ey * column_exp[u];
      value[u] = static_cast<float>(v);
      sigma[u] = static_cast<float>(noise_sigma_at(read, scale, g, v));
    }
  };
  if (gain > 0) {
    row(gain);
  } else {
    row(0.0);
  }
}

template <typename F>
void for_each_disk_pixel(Vec2 c, double r, F&& f) {
  const int y0 = static_cast<int>(std::ceil(c.y - r));
  const int y1 = static_cast<int>(std::floor(c.y + r));
  for (int y = y0; y <= y1; ++y) {
    const int x0 = static_cast<int>(std::ceil(c.x - r));
    const int x1 = static_cast<int>(std::floor(c.x + r));
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - c.x;
      const double dy = y - c.y;
      if (dx * dx + dy * dy <= r * r) f(x, y);
    }
  }
}

constexpr std::size_t kCones = 8;

// A contact of `area` px^2 at (x, y) at `level`. Below half a pixel's radius it is drawn at half a
// pixel, dimmer by the ratio of the areas: its light stays in proportion to its area and does
// not jump when it appears.
FeelerContact feeler_contact(double x, double y, double area, double level) {
  const double r = std::sqrt(std::max(area, 0.0) / std::numbers::pi);
  const double drawn = std::max(r, 0.5);
  return {x, y, drawn, level * (r * r) / (drawn * drawn)};
}

}  // namespace

// The load, as the area L = p / level it would collapse, flattens the column first, whose area
// saturates at pi r_c^2; the cones touch beyond L_on and share L - L_on by the tilt: the leading
// side (towards the shear) carries more, the trailing side less.
FeelerCluster feeler_cluster(const FeelerParams& f, double scale, double p, double cx, double cy,
                             double ux_mm, double uy_mm) {
  const double level = f.contact_level * scale;
  const double load = std::max(p, 0.0) / level;
  const double column_max = std::numbers::pi * f.column_radius_px * f.column_radius_px;
  const double column = column_max * -std::expm1(-load / column_max);
  const double cones = std::max(load - f.cone_onset * column_max, 0.0);
  const double u = std::hypot(ux_mm, uy_mm);
  const double tilt = f.tilt_share * std::min(u / f.tilt_mm, 1.0);
  const double ex = u > 0 ? ux_mm / u : 0.0;
  const double ey = u > 0 ? uy_mm / u : 0.0;
  FeelerCluster c;
  c[0] = feeler_contact(cx, cy, column, level);
  for (std::size_t i = 0; i < kCones; ++i) {
    const double a = 2.0 * std::numbers::pi * static_cast<double>(i) / kCones;
    const double share = (1.0 + tilt * (std::cos(a) * ex + std::sin(a) * ey)) / kCones;
    c[i + 1] = feeler_contact(cx + f.cone_circle_px * std::cos(a),
                              cy + f.cone_circle_px * std::sin(a), cones * share, level);
  }
  return c;
}

namespace {

// A contact's increment at pixel centre (x, y): its level times a one-pixel linear edge, so the
// image moves smoothly with the contact (no aliasing of the edge).
double contact_increment(const FeelerContact& c, double x, double y) {
  const double d = std::hypot(x - c.x, y - c.y);
  return c.level * std::clamp(c.r - d + 0.5, 0.0, 1.0);
}

}  // namespace

double cluster_increment(const FeelerCluster& cluster, double x, double y) {
  double s = 0;
  for (const FeelerContact& c : cluster)
    s += contact_increment(c, x, y);
  return s;
}

const char* to_string(ElementModel m) {
  switch (m) {
    case ElementModel::kGaussian:
      return "gaussian";
    case ElementModel::kFeelers:
      return "feelers";
  }
  return "?";
}

std::optional<ElementModel> element_model_from_string(std::string_view name) {
  for (auto m : {ElementModel::kGaussian, ElementModel::kFeelers}) {
    if (name == to_string(m)) return m;
  }
  return std::nullopt;
}

double level_scale(int bit_depth) {
  return bit_depth == 16 ? 257.0 : 1.0;
}

Calibration as_calibrated(const Calibration& truth, const SensorOpticsParams& opt) {
  Calibration cal = truth;
  const auto scaled = [](const PiecewiseLinear& c, double error) {
    std::vector<double> y(c.y().begin(), c.y().end());
    for (double& v : y)
      v *= 1.0 + error;
    return PiecewiseLinear(std::vector<double>(c.x().begin(), c.x().end()), std::move(y));
  };
  cal.normal_curve = scaled(truth.normal_curve, opt.normal_curve_error);
  cal.shear_curve = scaled(truth.shear_curve, opt.shear_curve_error);
  for (ElementCalibration& e : cal.elements) {
    e.center_px = {e.center_px.x + opt.layout_offset_px.x, e.center_px.y + opt.layout_offset_px.y};
    e.zero_px = {e.zero_px.x + opt.layout_offset_px.x, e.zero_px.y + opt.layout_offset_px.y};
  }
  return cal;
}

Calibration make_calibration(const std::string& sensor_id, const CameraParams& cam,
                             const SensorOpticsParams& opt, std::span<const Vec3> normals) {
  std::size_t expected = 0;
  for (int n : kRingCount)
    expected += static_cast<std::size_t>(n);
  if (normals.size() != expected) {
    throw std::invalid_argument("make_calibration: expected 41 element normals");
  }
  const double scale = level_scale(cam.bit_depth);
  Calibration cal;
  cal.sensor_id = sensor_id;
  cal.width = cam.width;
  cal.height = cam.height;
  cal.bit_depth = cam.bit_depth;
  cal.mm_per_px = opt.mm_per_px;
  const double bg_sigma =
      std::sqrt(cam.noise_sigma * cam.noise_sigma +
                (cam.shot_noise_gain > 0 ? cam.background / cam.shot_noise_gain : 0.0));
  cal.noise_floor = scale * std::max(opt.noise_floor_min, opt.noise_floor_sigmas * bg_sigma);
  // The contact thresholds hold for read noise of 2 gray levels and grow in proportion to the
  // noise beyond it: the dimmest spot in contact then keeps its peak-to-noise ratio, and with it
  // the centroid's noise and the rate of false slips (the Cramer-Rao bound: sigma_x ~ sigma_n / A).
  const double noise_scale = std::max(1.0, bg_sigma / 2.0);
  cal.contact_on = scale * opt.contact_on * noise_scale;
  cal.contact_off = scale * opt.contact_off * noise_scale;
  cal.normal_curve =
      PiecewiseLinear({0, 2000 * scale, 8000 * scale, 20000 * scale}, {0, 0.2, 1.0, 3.0});
  cal.shear_curve = PiecewiseLinear({0, 0.02, 0.08}, {0, 0.05, 0.4});
  const Vec2 centre{(cam.width - 1) / 2.0, (cam.height - 1) / 2.0};
  const double ring_scale = std::min(cam.width, cam.height) / 480.0;
  std::size_t k = 0;
  for (std::size_t ring = 0; ring < kRingCount.size(); ++ring) {
    for (int j = 0; j < kRingCount[ring]; ++j, ++k) {
      const Vec3 n = normals[k];
      const double phi = std::atan2(n.y, n.x);
      const double r = opt.ring_radius_px[ring] * ring_scale;
      ElementCalibration e;
      e.id = static_cast<std::uint32_t>(k);
      e.center_px = {centre.x + r * std::cos(phi), centre.y + r * std::sin(phi)};
      e.radius_px = opt.disk_radius_px;
      e.zero_px = e.center_px;
      e.normal = n;
      cal.elements.push_back(e);
    }
  }
  validate(cal);
  return cal;
}

Renderer::Renderer(const Calibration& cal, const CameraParams& cam, const SensorOpticsParams& opt,
                   std::uint64_t noise_seed)
    : cal_(cal), cam_(cam), opt_(opt) {
  validate(cal_);
  if (cam_.width != cal_.width || cam_.height != cal_.height || cam_.bit_depth != cal_.bit_depth)
    throw std::invalid_argument("Renderer: camera geometry differs from the calibration");
  scale_ = level_scale(cam_.bit_depth);
  max_level_ = cam_.bit_depth == 16 ? 65535.0 : 255.0;

  util::Random noise(noise_seed);
  pool_.resize(kPoolSize);
  for (float& z : pool_)
    z = static_cast<float>(noise.normal());

  background_.resize(static_cast<std::size_t>(cam_.width) * static_cast<std::size_t>(cam_.height));
  for (int y = 0; y < cam_.height; ++y)
    for (int x = 0; x < cam_.width; ++x)
      background_[static_cast<std::size_t>(y) * static_cast<std::size_t>(cam_.width) +
                  static_cast<std::size_t>(x)] = static_cast<float>(background_at(x, y));

  background_sigma_.resize(background_.size());
  for (std::size_t i = 0; i < background_.size(); ++i)
    background_sigma_[i] = static_cast<float>(pixel_sigma(static_cast<double>(background_[i])));
  read_sigma_ = static_cast<float>(pixel_sigma(0.0));

  // The background bank (CameraParams::refresh_outside_disks), from its own generator.
  bank_rng_.reseed(noise_seed ^ 0xB4C6'0F5E'2A17'93D1ULL);
  const std::size_t pixels = background_.size();
  const std::size_t pixel_bytes = cam_.bit_depth == 16 ? 2 : 1;
  const std::size_t bank =
      cam_.live_background && !cam_.refresh_outside_disks ? kBackgroundBank : 0;
  background_bank_.resize(bank * pixels * pixel_bytes);
  for (std::size_t f = 0; f < bank; ++f) {
    for (int y = 0; y < cam_.height; ++y) {
      std::size_t o = bank_rng_.below(kPoolSize - static_cast<std::size_t>(cam_.width));
      for (int x = 0; x < cam_.width; ++x, ++o) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(cam_.width) +
                              static_cast<std::size_t>(x);
        const double bg = static_cast<double>(background_[i]);
        const double v = std::clamp(
            std::nearbyint(bg + pixel_sigma(bg) * static_cast<double>(pool_[o])), 0.0, max_level_);
        if (pixel_bytes == 1) {
          background_bank_[f * pixels + i] = static_cast<std::uint8_t>(v);
        } else {
          const auto p16 = static_cast<std::uint16_t>(v);
          std::memcpy(background_bank_.data() + 2 * (f * pixels + i), &p16, 2);
        }
      }
    }
  }

  std::size_t offset = 0;
  for (const ElementCalibration& e : cal_.elements) {
    Box b{};
    b.x0 = std::max(0, static_cast<int>(std::floor(e.center_px.x - e.radius_px)) - 1);
    b.y0 = std::max(0, static_cast<int>(std::floor(e.center_px.y - e.radius_px)) - 1);
    b.x1 = std::min(cam_.width - 1, static_cast<int>(std::ceil(e.center_px.x + e.radius_px)) + 1);
    b.y1 = std::min(cam_.height - 1, static_cast<int>(std::ceil(e.center_px.y + e.radius_px)) + 1);
    b.offset = offset;
    offset += static_cast<std::size_t>(b.x1 - b.x0 + 1) * static_cast<std::size_t>(b.y1 - b.y0 + 1);
    b.span_offset = spans_.size();
    spans_.resize(spans_.size() + static_cast<std::size_t>(b.y1 - b.y0 + 1), Span{0, 0});
    for (const DiskRow& row : disk_rows(e.center_px, e.radius_px)) {
      if (row.y < b.y0 || row.y > b.y1) continue;
      const int x0 = std::clamp(row.x0, b.x0, b.x1 + 1) - b.x0;
      const int x1 = std::clamp(row.x1, b.x0, b.x1 + 1) - b.x0;
      spans_[b.span_offset + static_cast<std::size_t>(row.y - b.y0)] = {x0, std::max(x0, x1)};
    }
    column_exp_.resize(std::max(column_exp_.size(), static_cast<std::size_t>(b.x1 - b.x0 + 1)));
    boxes_.push_back(b);
  }
  cache_value_.assign(offset, 0.0F);
  cache_sigma_.assign(offset, 0.0F);
  std::size_t largest_box = 0;
  for (const Box& b : boxes_)
    largest_box = std::max(largest_box, static_cast<std::size_t>(b.x1 - b.x0 + 1) *
                                            static_cast<std::size_t>(b.y1 - b.y0 + 1));
  increment_.assign(largest_box, 0.0F);
  centroid_px_.resize(cal_.elements.size());
  for (std::size_t k = 0; k < cal_.elements.size(); ++k)
    centroid_px_[k] = cal_.elements[k].zero_px;
  last_.assign(cal_.elements.size(), ElementLoad{});
  drawn_.assign(cal_.elements.size(), false);

  // Expected measured G against drawn strength, per element: every disk pixel's expected
  // thresholded increment, with the noise of frame and reference and the rounding included.
  strength_grid_.push_back(0.0);
  for (int i = 0; i <= 80; ++i)
    strength_grid_.push_back(scale_ * std::pow(10.0, 6.5 * i / 80.0));
  const double n_ref = std::max(1, opt_.reference_frames);
  const double ref_factor = 1.0 + 1.0 / n_ref;
  const auto variance = [&](double bg, double s) {
    const double sd = pixel_sigma(bg + s);
    const double sd_ref = pixel_sigma(bg);
    return sd * sd + (ref_factor - 1.0) * sd_ref * sd_ref + ref_factor / 12.0;
  };
  struct DiskPixel {
    double dx, dy, r2, bg, base;
  };
  std::vector<DiskPixel> disk;
  g_table_.resize(cal_.elements.size());
  for (std::size_t k = 0; k < cal_.elements.size(); ++k) {
    const ElementCalibration& e = cal_.elements[k];
    disk.clear();
    double base_sum = 0;
    for_each_disk_pixel(e.center_px, e.radius_px, [&](int x, int y) {
      const double dx = x - e.center_px.x;
      const double dy = y - e.center_px.y;
      const double bg = background_at(x, y);
      const double base = partial_expectation(0.0, cal_.noise_floor, std::sqrt(variance(bg, 0)));
      disk.push_back({dx, dy, dx * dx + dy * dy, bg, base});
      base_sum += base;
    });
    auto& table = g_table_[k];
    table.reserve(strength_grid_.size());
    for (double p : strength_grid_) {
      if (opt_.element_model == ElementModel::kFeelers) {
        // The cluster unsheared, about the disk's centre (its G hardly moves with the shear:
        // the cones' shares sum to one).
        const FeelerCluster cluster = feeler_cluster(opt_.feelers, scale_, p, 0.0, 0.0, 0.0, 0.0);
        double g = base_sum;
        for (const DiskPixel& d : disk) {
          const double s = std::min(cluster_increment(cluster, d.dx, d.dy), max_level_ - d.bg);
          if (s < 1e-4 * scale_) continue;
          g += partial_expectation(s, cal_.noise_floor, std::sqrt(variance(d.bg, s))) - d.base;
        }
        if (!table.empty()) g = std::max(g, table.back());
        table.push_back(g);
        continue;
      }
      const double peak_ref = opt_.spot_peak_ref * scale_;
      const double sigma = std::clamp(std::sqrt(p / (2.0 * std::numbers::pi * peak_ref)),
                                      opt_.spot_sigma_min_px, opt_.spot_sigma_max_px);
      const double peak = p / (2.0 * std::numbers::pi * sigma * sigma);
      // Pixels the spot does not reach keep the noise's own expected weight (base).
      double g = base_sum;
      for (const DiskPixel& d : disk) {
        const double s = std::min(peak * std::exp(-d.r2 / (2 * sigma * sigma)), max_level_ - d.bg);
        if (s < 1e-4 * scale_) continue;
        g += partial_expectation(s, cal_.noise_floor, std::sqrt(variance(d.bg, s))) - d.base;
      }
      // Monotonic by construction; guard against rounding at the saturated end.
      if (!table.empty()) g = std::max(g, table.back());
      table.push_back(g);
    }
  }
}

double Renderer::background_at(double x, double y) const {
  const double cx = (cam_.width - 1) / 2.0;
  const double cy = (cam_.height - 1) / 2.0;
  const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (cx * cx + cy * cy);
  return scale_ * cam_.background * (1.0 - cam_.vignetting * r2);
}

double Renderer::pixel_sigma(double value_levels) const {
  return noise_sigma_at(scale_ * cam_.noise_sigma, scale_, cam_.shot_noise_gain, value_levels);
}

double Renderer::expected_g(std::size_t k, double p) const {
  const auto& t = g_table_[k];
  const auto& s = strength_grid_;
  if (p <= 0) return t.front();
  const auto it = std::upper_bound(s.begin(), s.end(), p);
  if (it == s.end()) {
    const std::size_t n = s.size();
    return t[n - 1] + (p - s[n - 1]) * (t[n - 1] - t[n - 2]) / (s[n - 1] - s[n - 2]);
  }
  const auto i = static_cast<std::size_t>(it - s.begin());
  const double w = (p - s[i - 1]) / (s[i] - s[i - 1]);
  return t[i - 1] + w * (t[i] - t[i - 1]);
}

double Renderer::strength_for_g(std::size_t k, double g) const {
  const auto& t = g_table_[k];
  const auto& s = strength_grid_;
  if (!(g > t.front())) return 0.0;
  const auto it = std::upper_bound(t.begin(), t.end(), g);
  if (it == t.end()) {
    const std::size_t n = t.size();
    const double slope = (t[n - 1] - t[n - 2]) / (s[n - 1] - s[n - 2]);
    return slope > 0 ? s[n - 1] + (g - t[n - 1]) / slope : s[n - 1];
  }
  const auto i = static_cast<std::size_t>(it - t.begin());
  const double dt = t[i] - t[i - 1];
  const double w = dt > 0 ? (g - t[i - 1]) / dt : 0.0;
  return s[i - 1] + w * (s[i] - s[i - 1]);
}

void Renderer::draw_spot(std::size_t k, const ElementLoad& load) {
  const ElementCalibration& e = cal_.elements[k];
  const double fz = std::isfinite(load.fz_n) ? std::max(load.fz_n, 0.0) : 0.0;
  const double p = fz > 0 ? strength_for_g(k, cal_.normal_curve.inverse(fz)) : 0.0;
  const double ux = std::isfinite(load.ux_mm) ? load.ux_mm : 0.0;
  const double uy = std::isfinite(load.uy_mm) ? load.uy_mm : 0.0;
  const double cx = e.zero_px.x + ux / cal_.mm_per_px;
  const double cy = e.zero_px.y + uy / cal_.mm_per_px;
  if (opt_.element_model == ElementModel::kFeelers) {
    draw_feelers(k, p, cx, cy, ux, uy);
    centroid_from_cache(k, cx, cy);
  } else {
    // A Gaussian's light is centred on the spot: no pass over the box to find it.
    draw_gaussian(k, p, cx, cy);
    centroid_px_[k] = Vec2{cx, cy};
  }
}

void Renderer::draw_gaussian(std::size_t k, double p, double cx, double cy) {
  const Box& b = boxes_[k];
  const double peak_ref = opt_.spot_peak_ref * scale_;
  const double sigma = std::clamp(std::sqrt(p / (2.0 * std::numbers::pi * peak_ref)),
                                  opt_.spot_sigma_min_px, opt_.spot_sigma_max_px);
  const double peak = p / (2.0 * std::numbers::pi * sigma * sigma);
  const std::size_t w = static_cast<std::size_t>(b.x1 - b.x0 + 1);
  const double inv = 1.0 / (2.0 * sigma * sigma);
  // The spot is separable: exp(-dx^2 inv) once per column instead of once per pixel (the same
  // numbers), and only where a row's factor leaves it visible.
  if (peak > 0) {
    for (std::size_t j = 0; j < w; ++j) {
      const double dx = static_cast<double>(b.x0 + static_cast<int>(j)) - cx;
      column_exp_[j] = std::exp(-dx * dx * inv);
    }
  }
  for (int y = b.y0; y <= b.y1; ++y) {
    const Span& span = spans_[b.span_offset + static_cast<std::size_t>(y - b.y0)];
    if (span.x0 == span.x1) continue;
    const double ey = peak > 0 ? peak * std::exp(-(y - cy) * (y - cy) * inv) : 0.0;
    const std::size_t pixel = static_cast<std::size_t>(y) * cam_.width + b.x0;
    const float* bg = background_.data() + pixel;
    const std::size_t row = b.offset + static_cast<std::size_t>(y - b.y0) * w;
    if (!(ey > 1e-6)) {
      // A row the spot does not reach: the background and its sigma as they are.
      const auto j0 = static_cast<std::size_t>(span.x0);
      const auto n = static_cast<std::size_t>(span.x1 - span.x0);
      std::copy_n(bg + j0, n, cache_value_.begin() + static_cast<std::ptrdiff_t>(row + j0));
      std::copy_n(background_sigma_.begin() + static_cast<std::ptrdiff_t>(pixel + j0), n,
                  cache_sigma_.begin() + static_cast<std::ptrdiff_t>(row + j0));
      continue;
    }
    spot_row(bg, column_exp_.data(), ey, scale_ * cam_.noise_sigma, scale_, cam_.shot_noise_gain,
             static_cast<std::size_t>(span.x0), static_cast<std::size_t>(span.x1),
             cache_value_.data() + row, cache_sigma_.data() + row);
  }
}

void Renderer::draw_feelers(std::size_t k, double p, double cx, double cy, double ux_mm,
                            double uy_mm) {
  const Box& b = boxes_[k];
  const auto w = static_cast<std::size_t>(b.x1 - b.x0 + 1);
  const auto h = static_cast<std::size_t>(b.y1 - b.y0 + 1);
  std::fill_n(increment_.begin(), static_cast<std::ptrdiff_t>(w * h), 0.0F);
  // Each contact only over its own bounding box (within the element's box).
  for (const FeelerContact& c : feeler_cluster(opt_.feelers, scale_, p, cx, cy, ux_mm, uy_mm)) {
    if (!(c.level > 0)) continue;
    const int x0 = std::max(b.x0, static_cast<int>(std::floor(c.x - c.r - 0.5)));
    const int x1 = std::min(b.x1, static_cast<int>(std::ceil(c.x + c.r + 0.5)));
    const int y0 = std::max(b.y0, static_cast<int>(std::floor(c.y - c.r - 0.5)));
    const int y1 = std::min(b.y1, static_cast<int>(std::ceil(c.y + c.r + 0.5)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        increment_[static_cast<std::size_t>(y - b.y0) * w + static_cast<std::size_t>(x - b.x0)] +=
            static_cast<float>(contact_increment(c, x, y));
  }
  for (int y = b.y0; y <= b.y1; ++y) {
    const Span& span = spans_[b.span_offset + static_cast<std::size_t>(y - b.y0)];
    const std::size_t pixel = static_cast<std::size_t>(y) * cam_.width + b.x0;
    const std::size_t row = static_cast<std::size_t>(y - b.y0) * w;
    for (int j = span.x0; j < span.x1; ++j) {
      const auto u = static_cast<std::size_t>(j);
      const double v =
          static_cast<double>(background_[pixel + u]) + static_cast<double>(increment_[row + u]);
      cache_value_[b.offset + row + u] = static_cast<float>(v);
      cache_sigma_[b.offset + row + u] = static_cast<float>(pixel_sigma(v));
    }
  }
}

void Renderer::centroid_from_cache(std::size_t k, double cx, double cy) {
  const Box& b = boxes_[k];
  const auto w = static_cast<std::size_t>(b.x1 - b.x0 + 1);
  double sum = 0, sx = 0, sy = 0;
  for (int y = b.y0; y <= b.y1; ++y) {
    const Span& span = spans_[b.span_offset + static_cast<std::size_t>(y - b.y0)];
    const std::size_t pixel = static_cast<std::size_t>(y) * cam_.width + b.x0;
    const std::size_t row = b.offset + static_cast<std::size_t>(y - b.y0) * w;
    for (int j = span.x0; j < span.x1; ++j) {
      const auto u = static_cast<std::size_t>(j);
      const double dg =
          static_cast<double>(cache_value_[row + u]) - static_cast<double>(background_[pixel + u]);
      sum += dg;
      sx += dg * (b.x0 + j);
      sy += dg * y;
    }
  }
  centroid_px_[k] = sum > 0 ? Vec2{sx / sum, sy / sum} : Vec2{cx, cy};
}

void Renderer::render(std::span<const ElementLoad> loads, util::Random& rng, Image& out) {
  const PixelFormat fmt = cam_.bit_depth == 16 ? PixelFormat::kMono16 : PixelFormat::kMono8;
  if (out.width() != cam_.width || out.height() != cam_.height || out.format() != fmt) {
    out = Image(cam_.width, cam_.height, fmt);
    first_ = true;
  }
  const auto quantise = [this](double v) {
    return static_cast<std::uint32_t>(std::clamp(std::nearbyint(v), 0.0, max_level_));
  };
  if (first_ || cam_.refresh_outside_disks) {
    for (int y = 0; y < cam_.height; ++y) {
      std::size_t o = rng.below(kPoolSize - static_cast<std::size_t>(cam_.width));
      const float* bg = background_.data() + static_cast<std::size_t>(y) * cam_.width;
      for (int x = 0; x < cam_.width; ++x, ++o)
        out.set(x, y,
                quantise(static_cast<double>(bg[x]) +
                         pixel_sigma(static_cast<double>(bg[x])) * static_cast<double>(pool_[o])));
    }
    first_ = false;
  } else if (!background_bank_.empty()) {
    // A live background: each row from one of the bank's frames (the disks are drawn over it).
    const std::size_t row_bytes = out.stride_bytes();
    const std::size_t frame_bytes = row_bytes * static_cast<std::size_t>(cam_.height);
    std::uint8_t* dst = out.bytes().data();
    for (int y = 0; y < cam_.height; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * row_bytes;
      std::memcpy(dst + row,
                  background_bank_.data() + bank_rng_.below(kBackgroundBank) * frame_bytes + row,
                  row_bytes);
    }
  }
  redrawn_ = 0;
  for (std::size_t k = 0; k < boxes_.size(); ++k) {
    const ElementLoad load = k < loads.size() ? loads[k] : ElementLoad{};
    const ElementLoad& prev = last_[k];
    if (!drawn_[k] || load.fz_n != prev.fz_n || load.ux_mm != prev.ux_mm ||
        load.uy_mm != prev.uy_mm) {
      draw_spot(k, load);
      last_[k] = load;
      drawn_[k] = true;
      ++redrawn_;
    }
    if (fmt == PixelFormat::kMono8) {
      noisy_box<std::uint8_t>(k, rng, out);
    } else {
      noisy_box<std::uint16_t>(k, rng, out);
    }
  }
}

template <typename Pixel>
void Renderer::noisy_box(std::size_t k, util::Random& rng, Image& out) const noexcept {
  const Box& b = boxes_[k];
  const std::size_t w = static_cast<std::size_t>(b.x1 - b.x0 + 1);
  const std::size_t n = w * static_cast<std::size_t>(b.y1 - b.y0 + 1);
  const float* z = pool_.data() + rng.below(kPoolSize - n);
  const float* value = cache_value_.data() + b.offset;
  // Without shot noise every pixel's sigma is the read noise's (pixel_sigma).
  const bool one_sigma = !(cam_.shot_noise_gain > 0);
  const float* sigma = one_sigma ? &read_sigma_ : cache_sigma_.data() + b.offset;
  const auto top = static_cast<float>(max_level_);
  const auto stride = static_cast<std::size_t>(cam_.width);
  Pixel* row = reinterpret_cast<Pixel*>(out.bytes().data()) +
               static_cast<std::size_t>(b.y0) * stride + static_cast<std::size_t>(b.x0);
  const Span* spans = spans_.data() + b.span_offset;
  const int rows = b.y1 - b.y0 + 1;
  noisy_pixels(value, sigma, one_sigma, z, spans, rows, w, row, stride, top);
}

}  // namespace tactile::rig
