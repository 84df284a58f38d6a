#pragma once

// Scenario files for the rig (a fixed interface; every key and default in docs/rig.md).
#include <array>
#include <cstdint>
#include <filesystem>
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

// Parses a scenario; every error throws config::ConfigError naming the file, line, key and
// value. Unknown keys are refused (a typo would silently change an experiment).
Scenario parse_scenario(const std::string& text, const std::string& source);
Scenario load_scenario(const std::filesystem::path& path);

}  // namespace tactile::rig
