#pragma once

// Scenario files for the rig (a fixed interface; every key and default in docs/rig.md).
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "tactile/rig/optics.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {

inline constexpr const char* kScenarioFormat = "tactile-scenario/1";

// When a disturbance timed from a stage of the task starts (docs/rig.md, "Disturbances and
// fragile objects"): after_s after the controller entered `stage` (a control::to_string(Phase)
// name) for the first time. An empty stage: the start is on the run's clock, in the world's
// DisturbanceParams already.
struct DisturbanceStart {
  std::string stage;
  double after_s = 0;
};

struct Scenario {
  std::string source;  // file name, for messages
  std::uint64_t seed = 1;
  WorldParams world;
  CameraParams camera;
  SensorOpticsParams optics;
  // sensor.calibration: a lab's calibration file, resolved against the scenario file's folder
  // (docs/rig.md, "A lab's sensor"). Both fingertips render it instead of make_calibration's;
  // empty and nullopt: the rig's own sensor.
  std::filesystem::path calibration_file;
  std::optional<Calibration> calibration;
  double dt_s = 1e-4;         // physics step; a frame period holds a whole number of steps
  double max_time_s = 120.0;  // simulated time after which a run stops, incomplete
  double settle_after_done_s = 0.3;
  // Ground truth: a moving contact loaded beyond this share of its static limit is slipping.
  double partial_slip_ratio = 0.1;
  // Controller settings the scenario overrides (names as in the `controller` section; the
  // lockstep runner maps them onto the control core's Config).
  std::vector<std::pair<std::string, double>> controller;
  // controller.slip_detector (paper, field, learned); empty: the control core's default.
  std::string slip_detector;
  // controller.grip (paper, margin); empty: the control core's default.
  std::string grip;
  // The disturbances' starts by stage, indexed by DisturbanceKind (their forces, masses and
  // absolute starts are in world.disturbance).
  std::array<DisturbanceStart, 3> disturbance_start;

  // Physics steps per camera frame and the step that makes them fit exactly.
  int steps_per_frame() const;
  double step_s() const;
};

// Names the `controller` section accepts.
const std::vector<std::string>& controller_keys();

// A lab's sensor as a run names it (docs/rig.md, "A lab's sensor"): its calibration file and the
// image the file gives the cameras (the report's `sensor`; the sweep's and slip_train's scenario
// files).
struct LabSensor {
  std::string calibration;
  int width = 0;
  int height = 0;
  int bit_depth = 0;
};

// How far a lab calibration's element normal may lie from the rig fingertip's (degrees): under
// half the angle between neighbouring elements of the dome (10 degrees between rings), so element
// k of the file can only be the world's element k.
inline constexpr double kLabNormalToleranceDeg = 5.0;

// Refuses a lab's calibration the rig's fingertip cannot render (docs/rig.md, "A lab's sensor"):
// another element count than the world's 41, or an element whose normal lies more than
// kLabNormalToleranceDeg from the world's element of the same place in the list. Throws
// config::ConfigError naming `source`, the key, the element and the value.
void check_lab_calibration(const Calibration& cal, const std::string& source,
                           std::span<const Vec3> world_normals);
// Loads a lab's calibration file (config::load_calibration) and checks it against the fingertip
// of `world` (check_lab_calibration). Throws config::ConfigError naming the file.
Calibration load_lab_calibration(const std::filesystem::path& file, const WorldParams& world);
// The same for `rig --sweep --calibration FILE` and `slip_train --calibration FILE`, at start-up:
// the file, made absolute (every scenario file and child process names it so), and its image.
LabSensor load_lab_sensor(const std::filesystem::path& file, const WorldParams& world = {});

// Parses a scenario; every error throws config::ConfigError naming the file, line, key and
// value. Unknown keys are refused (a typo would silently change an experiment).
Scenario parse_scenario(const std::string& text, const std::string& source);
Scenario load_scenario(const std::filesystem::path& path);

}  // namespace tactile::rig
