#pragma once

// The simulated sensors of a rig run, set up once for the lockstep runner and the real-time rig
// alike (architecture.md, rule 9): both fingertips' calibrations, renderers and per-frame noise
// generators (seeds mixed from the scenario's seed), and the truth recorder at the sensors' own
// contact threshold.
#include <array>
#include <filesystem>
#include <span>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/image.hpp"
#include "tactile/rig/optics.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/truth.hpp"
#include "tactile/util/random.hpp"

namespace tactile::rig {

// The fingertips' sensor ids, in fingertip order.
inline constexpr std::array<const char*, kFingertips> kFingertipIds{"left", "right"};

// The two simulated sensors' true calibrations for this scenario and camera, the ones they are
// rendered with: make_calibration's, or the scenario's sensor.calibration under each
// fingertip's id.
std::array<Calibration, kFingertips> rendered_calibrations(const Scenario& scenario,
                                                           const CameraParams& camera,
                                                           std::span<const Vec3> normals);
// The calibrations sensor_node and hand_node are given: the rendered ones with the scenario's
// calibration error (as_calibrated). Throws std::runtime_error, naming the file and
// sensor.layout_offset_px, when the offset moves a disk off the image.
std::array<Calibration, kFingertips> simulated_calibrations(const Scenario& scenario,
                                                            const CameraParams& camera,
                                                            std::span<const Vec3> normals);
// Writes each as `dir`/<sensor_id>.yaml (tactile-calibration/1), the files sensor_node and
// hand_node load; returns the paths written. Throws when a file cannot be written.
std::vector<std::filesystem::path> save_calibrations(
    const std::filesystem::path& dir, const std::array<Calibration, kFingertips>& calibrations);

class SimulatedSensors {
 public:
  // `camera`: the scenario's camera, or one the real-time rig changed (refresh_outside_disks).
  SimulatedSensors(const Scenario& scenario, const CameraParams& camera,
                   std::span<const Vec3> normals);

  // The calibrations the measurement is given (simulated_calibrations).
  const std::array<Calibration, kFingertips>& calibrations() const { return calibrations_; }
  TruthRecorder& truth() { return truth_; }
  // Renders fingertip i's image of the loads in `truth` (all zero: no load). Allocates nothing
  // once the image has its size.
  const Image& render(std::size_t fingertip, const FingertipTruth& truth);
  // The truth's shear displacement as the image defines it, after render(fingertip, truth):
  // with the feeler element model, each element's (u_x, u_y) becomes the paper's eq. 3-4 on its
  // noiseless image less zero_px, in mm (the cluster's light is not centred on its deflection);
  // with the Gaussian model it stays the deflection. Allocates nothing.
  void image_truth(std::size_t fingertip, FingertipTruth& truth) const;

 private:
  std::array<Calibration, kFingertips> rendered_;
  std::array<Calibration, kFingertips> calibrations_;
  std::vector<Renderer> renderers_;
  std::array<util::Random, kFingertips> frame_rng_;
  std::array<Image, kFingertips> images_;
  std::array<ElementLoad, kElementsPerFingertip> loads_{};
  TruthRecorder truth_;
  ElementModel element_model_;
};

}  // namespace tactile::rig
