#include "tactile/rig/sensors.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "tactile/config/calibration_file.hpp"
#include "tactile/util/random.hpp"

namespace tactile::rig {
namespace {

double visible_fz_n(const Calibration& cal) {
  return cal.normal_curve(cal.contact_on);
}

// The rendered calibrations as the measurement is given them (the scenario's calibration error).
std::array<Calibration, kFingertips> given_calibrations(
    const Scenario& sc, const std::array<Calibration, kFingertips>& rendered) {
  std::array<Calibration, kFingertips> cals;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    cals[i] = as_calibrated(rendered[i], sc.optics);
    try {
      validate(cals[i]);
    } catch (const CalibrationError& e) {
      throw std::runtime_error(fmt::format(
          "{}: sensor.layout_offset_px [{}, {}] moves {}'s calibration off its image: {}",
          sc.source, sc.optics.layout_offset_px.x, sc.optics.layout_offset_px.y, cals[i].sensor_id,
          e.what()));
    }
  }
  return cals;
}

}  // namespace

std::array<Calibration, kFingertips> rendered_calibrations(const Scenario& sc,
                                                           const CameraParams& camera,
                                                           std::span<const Vec3> normals) {
  std::array<Calibration, kFingertips> cals;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    if (sc.calibration) {
      // A lab's sensor (sensor.calibration): one file for both fingertips, each under its own
      // id, as the rig's sensor_node and hand_node configurations name them.
      cals[i] = *sc.calibration;
      cals[i].sensor_id = kFingertipIds[i];
    } else {
      cals[i] = make_calibration(kFingertipIds[i], camera, sc.optics, normals);
    }
  }
  return cals;
}

std::array<Calibration, kFingertips> simulated_calibrations(const Scenario& sc,
                                                            const CameraParams& camera,
                                                            std::span<const Vec3> normals) {
  return given_calibrations(sc, rendered_calibrations(sc, camera, normals));
}

std::vector<std::filesystem::path> save_calibrations(
    const std::filesystem::path& dir, const std::array<Calibration, kFingertips>& calibrations) {
  std::vector<std::filesystem::path> paths;
  for (const Calibration& cal : calibrations) {
    paths.push_back(dir / (cal.sensor_id + ".yaml"));
    config::save_calibration(paths.back(), cal);
  }
  return paths;
}

SimulatedSensors::SimulatedSensors(const Scenario& sc, const CameraParams& camera,
                                   std::span<const Vec3> normals)
    : rendered_(rendered_calibrations(sc, camera, normals)),
      calibrations_(given_calibrations(sc, rendered_)),
      frame_rng_{util::Random(util::splitmix64(sc.seed * 4 + 1)),
                 util::Random(util::splitmix64(sc.seed * 4 + 2))},
      truth_(visible_fz_n(rendered_[0]), sc.partial_slip_ratio),
      element_model_(sc.optics.element_model) {
  for (std::size_t i = 0; i < kFingertips; ++i)
    renderers_.emplace_back(rendered_[i], camera, sc.optics,
                            util::splitmix64(sc.seed * 4 + 3 + i * 7919));
}

const Image& SimulatedSensors::render(std::size_t i, const FingertipTruth& truth) {
  for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
    const ElementTruth& et = truth.elements[k];
    loads_[k] = {et.fz_n, et.ux_mm, et.uy_mm};
  }
  renderers_[i].render(loads_, frame_rng_[i], images_[i]);
  return images_[i];
}

void SimulatedSensors::image_truth(std::size_t i, FingertipTruth& truth) const {
  if (element_model_ != ElementModel::kFeelers) return;
  const Calibration& cal = rendered_[i];  // the truth is the sensor's, not its calibration's
  for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
    const Vec2 c = renderers_[i].noiseless_centroid_px(k);
    truth.elements[k].ux_mm = (c.x - cal.elements[k].zero_px.x) * cal.mm_per_px;
    truth.elements[k].uy_mm = (c.y - cal.elements[k].zero_px.y) * cal.mm_per_px;
  }
}

}  // namespace tactile::rig
