#include "synthetic.hpp"

#include <algorithm>
#include <cmath>

#include "tactile/rig/optics.hpp"

namespace tactile::testing {

double level_scale(int bit_depth) {
  return bit_depth == 16 ? 257.0 : 1.0;
}

double background_at(const SceneOptions& o, double x, double y) {
  const double cx = (o.width - 1) / 2.0;
  const double cy = (o.height - 1) / 2.0;
  const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (cx * cx + cy * cy);
  return o.background * (1.0 - o.vignetting * r2);
}

double spot_at(const Spot& s, double x, double y) {
  const double dx = x - s.center.x;
  const double dy = y - s.center.y;
  switch (s.shape) {
    case SpotShape::kGaussian:
      return s.peak * std::exp(-(dx * dx + dy * dy) / (2 * s.sigma * s.sigma));
    case SpotShape::kElliptical: {
      const double sy = s.sigma_y > 0 ? s.sigma_y : s.sigma;
      return s.peak * std::exp(-0.5 * (dx * dx / (s.sigma * s.sigma) + dy * dy / (sy * sy)));
    }
    case SpotShape::kFlatTop: {
      // A plateau with Gaussian shoulders: the look of a collapsed feeler's contact patch.
      const double r = std::hypot(dx, dy);
      if (r <= s.flat_radius) return s.peak;
      const double e = r - s.flat_radius;
      return s.peak * std::exp(-e * e / (2 * s.sigma * s.sigma));
    }
    case SpotShape::kFeelers: {
      rig::FeelerParams f;
      f.contact_level = s.peak;
      const rig::FeelerCluster c =
          rig::feeler_cluster(f, 1.0, s.feeler_load_px2 * s.peak, s.center.x, s.center.y, 0.0, 0.0);
      return rig::cluster_increment(c, x, y);
    }
  }
  return 0;
}

namespace {

std::uint32_t quantise(const SceneOptions& o, double v) {
  const double max_level = o.bit_depth == 16 ? 65535.0 : 255.0;
  return static_cast<std::uint32_t>(
      std::clamp(std::round(v * level_scale(o.bit_depth)), 0.0, max_level));
}

double reach_of(const Spot& s) {
  if (s.shape == SpotShape::kFeelers)
    return rig::FeelerParams{}.cone_circle_px + std::sqrt(s.feeler_load_px2) + 2;
  return 8 * std::max(s.sigma, s.sigma_y) + s.flat_radius + 2;
}

template <typename Spots>
void render_pixel(const SceneOptions& o, const Spots& spots, util::Random& rng, Image& out, int x,
                  int y) {
  double v = background_at(o, x, y);
  for (const Spot* s : spots) {
    const double reach = reach_of(*s);
    if (std::abs(x - s->center.x) < reach && std::abs(y - s->center.y) < reach)
      v += spot_at(*s, x, y);
  }
  if (o.shot_noise_gain > 0) v += std::sqrt(std::max(v, 0.0) / o.shot_noise_gain) * rng.normal();
  v += o.noise_sigma * rng.normal();
  out.set(x, y, quantise(o, v));
}

PixelFormat format_of(const SceneOptions& o) {
  return o.bit_depth == 16 ? PixelFormat::kMono16 : PixelFormat::kMono8;
}

}  // namespace

void render(const SceneOptions& o, const std::vector<Spot>& spots, util::Random& rng, Image& out,
            const Calibration* only) {
  if (only != nullptr) {
    SceneRenderer(o, only).render(spots, rng, out);
    return;
  }
  if (out.width() != o.width || out.height() != o.height || out.format() != format_of(o)) {
    out = Image(o.width, o.height, format_of(o));
  }
  std::vector<const Spot*> all;
  for (const Spot& s : spots)
    all.push_back(&s);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x)
      render_pixel(o, all, rng, out, x, y);
}

SceneRenderer::SceneRenderer(const SceneOptions& o, const Calibration* only)
    : o_(o), background_(o.width, o.height, format_of(o)) {
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x)
      background_.set(x, y, quantise(o, background_at(o, x, y)));
  if (only == nullptr) {
    boxes_.push_back({0, 0, o.width - 1, o.height - 1});
    return;
  }
  for (const ElementCalibration& e : only->elements) {
    boxes_.push_back(
        {std::max(0, static_cast<int>(std::floor(e.center_px.x - e.radius_px)) - 1),
         std::max(0, static_cast<int>(std::floor(e.center_px.y - e.radius_px)) - 1),
         std::min(o.width - 1, static_cast<int>(std::ceil(e.center_px.x + e.radius_px)) + 1),
         std::min(o.height - 1, static_cast<int>(std::ceil(e.center_px.y + e.radius_px)) + 1)});
  }
}

void SceneRenderer::render(const std::vector<Spot>& spots, util::Random& rng, Image& out) const {
  out = background_;  // reuses out's storage when the sizes match
  std::vector<const Spot*> near;
  for (const Box& b : boxes_) {
    near.clear();
    for (const Spot& s : spots) {
      const double reach = reach_of(s);
      if (s.center.x + reach > b.x0 && s.center.x - reach < b.x1 && s.center.y + reach > b.y0 &&
          s.center.y - reach < b.y1) {
        near.push_back(&s);
      }
    }
    for (int y = b.y0; y <= b.y1; ++y)
      for (int x = b.x0; x <= b.x1; ++x)
        render_pixel(o_, near, rng, out, x, y);
  }
}

Calibration grid_calibration(const SceneOptions& o, int cols, int rows, double spacing,
                             double radius) {
  Calibration cal;
  cal.sensor_id = "synthetic";
  cal.width = o.width;
  cal.height = o.height;
  cal.bit_depth = o.bit_depth;
  cal.mm_per_px = 0.025;
  const double scale = level_scale(o.bit_depth);
  cal.noise_floor = 4.0 * scale;
  cal.contact_on = 400.0 * scale;
  cal.contact_off = 250.0 * scale;
  cal.normal_curve =
      PiecewiseLinear({0, 2000 * scale, 8000 * scale, 20000 * scale}, {0, 0.2, 1.0, 3.0});
  cal.shear_curve = PiecewiseLinear({0, 0.02, 0.08}, {0, 0.05, 0.4});
  const double x0 = (o.width - 1) / 2.0 - spacing * (cols - 1) / 2.0;
  const double y0 = (o.height - 1) / 2.0 - spacing * (rows - 1) / 2.0;
  std::uint32_t id = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      ElementCalibration e;
      e.id = id++;
      e.center_px = {x0 + c * spacing, y0 + r * spacing};
      e.radius_px = radius;
      e.zero_px = e.center_px;
      e.normal = {0, 0, 1};
      cal.elements.push_back(e);
    }
  }
  return cal;
}

}  // namespace tactile::testing
