#include "scene.hpp"

#include <cmath>
#include <numbers>

namespace tactile::bench {

Calibration dome_calibration(const testing::SceneOptions& o, double radius_px,
                             double floor_sigmas) {
  Calibration cal = testing::grid_calibration(o, 1, 1, 1.0, radius_px);
  cal.sensor_id = "dome41";
  cal.noise_floor = floor_sigmas * o.noise_sigma * testing::level_scale(o.bit_depth);
  cal.elements.clear();
  const double cx = (o.width - 1) / 2.0;
  const double cy = (o.height - 1) / 2.0;
  std::uint32_t id = 0;
  const auto ring = [&](double r, int n, double phase) {
    for (int i = 0; i < n; ++i) {
      const double a = phase + 2 * std::numbers::pi * i / n;
      ElementCalibration e;
      e.id = id++;
      e.center_px = {cx + r * std::cos(a), cy + r * std::sin(a)};
      e.radius_px = radius_px;
      e.zero_px = e.center_px;
      e.normal = {0, 0, 1};
      cal.elements.push_back(e);
    }
  };
  ring(0, 1, 0);
  ring(55, 8, 0);
  ring(115, 16, 0.1);
  ring(180, 16, 0.3);
  validate(cal);
  return cal;
}

std::vector<std::size_t> press_order(std::size_t elements) {
  // Stride 17 is coprime with 41: one element from each ring in turn.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < elements; ++i)
    order.push_back((i * 17 + 3) % elements);
  return order;
}

std::vector<Method> methods() {
  using K = Method::Kind;
  using E = CentroidEstimator;
  std::vector<Method> m;
  const ExtractorOptions defaults;
  m.push_back({"gaussian", K::kCore, E::kGaussian, 2.0, defaults.window_margin_px,
               defaults.gaussian_reach_sigmas, true});
  m.push_back({"gaussian_reach3.5", K::kCore, E::kGaussian, 2.0, 2.0, 3.5, false});
  m.push_back({"gaussian_reach2.5", K::kCore, E::kGaussian, 2.0, 2.0, 2.5, false});
  m.push_back({"gaussian-axes", K::kCore, E::kGaussianAxes, 2.0, 2.0,
               defaults.gaussian_reach_sigmas, false});
  m.push_back({"plain", K::kCore, E::kPlain, 2.0, 2.0, 3.5, false});
  m.push_back({"thresholded", K::kCore, E::kThresholded, 2.0, 2.0, 3.5, false});
  m.push_back({"thresholded_floor3", K::kCore, E::kThresholded, 3.0, 2.0, 3.5, false});
  m.push_back({"windowed", K::kCore, E::kWindowed, 2.0, 2.0, 3.5, false});
  m.push_back({"windowed_margin1", K::kCore, E::kWindowed, 2.0, 1.0, 3.5, false});
  m.push_back({"opencv", K::kOpenCv, E::kThresholded, 2.0, 2.0, 3.5, false});
  m.push_back({"floor", K::kFloor, E::kThresholded, 2.0, 2.0, 3.5, false});
  return m;
}

const Method* find_method(const std::string& name) {
  static const std::vector<Method> all = methods();
  for (const Method& m : all)
    if (m.name == name) return &m;
  return nullptr;
}

ExtractorOptions options_for(const Method& m) {
  ExtractorOptions o;
  o.estimator = m.estimator;
  o.window_margin_px = m.window_margin_px;
  o.gaussian_reach_sigmas = m.gaussian_reach_sigmas;
  return o;
}

}  // namespace tactile::bench
