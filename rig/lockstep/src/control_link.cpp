#include "tactile/rig/control_link.hpp"

#include <stdexcept>

#include "tactile/config/controller_file.hpp"

namespace tactile::rig {

control::Config scenario_controller_config(const Scenario& sc) {
  control::Config cfg;
  cfg.cap_x_m = sc.world.cap.x_m;
  cfg.cap_y_m = sc.world.cap.y_m;
  cfg.bottle_x_m = sc.world.bottle.x_m;
  cfg.bottle_y_m = sc.world.bottle.y_m;
  cfg.tighten_clockwise = sc.world.bottle.tighten_clockwise;
  for (const auto& [key, v] : sc.controller) {
    if (!config::set_controller_field(cfg, key, v)) {
      throw std::invalid_argument(sc.source + ": controller." + key +
                                  " is not a controller setting");
    }
  }
  if (!sc.slip_detector.empty()) {
    const auto kind = control::slip_detector_from_string(sc.slip_detector);
    if (!kind) {
      throw std::invalid_argument(sc.source + ": controller.slip_detector = " + sc.slip_detector +
                                  ": must be " + control::kSlipDetectorNames);
    }
    cfg.slip_detector = *kind;
  }
  if (!sc.grip.empty()) {
    const auto kind = control::grip_from_string(sc.grip);
    if (!kind) {
      throw std::invalid_argument(sc.source + ": controller.grip = " + sc.grip + ": must be " +
                                  control::kGripNames);
    }
    cfg.grip = *kind;
  }
  cfg.validate();
  return cfg;
}

ArmCommand to_world_command(const control::Command& c) {
  ArmCommand a;
  switch (c.kind) {
    case control::CommandKind::kNone:
      a.kind = CommandKind::kNone;
      break;
    case control::CommandKind::kMoveTo:
      a.kind = CommandKind::kMoveTo;
      a.segment_id = c.move_to.segment_id;
      a.target_position_m = c.move_to.target.position_m;
      a.target_yaw_rad = c.move_to.target.yaw_rad;
      a.max_speed_mps = c.move_to.max_speed_mps;
      a.max_yaw_rate_rps = c.move_to.max_yaw_rate_rps;
      a.keep_finger_velocities = c.move_to.keep_finger_velocities;
      break;
    case control::CommandKind::kFingerVelocities:
      a.kind = CommandKind::kFingerVelocities;
      a.finger_velocity_mps = c.finger_velocities.velocity_mps;
      break;
    case control::CommandKind::kHold:
      a.kind = CommandKind::kHold;
      break;
    case control::CommandKind::kOpen:
      a.kind = CommandKind::kOpen;
      a.open_speed_mps = c.open.speed_mps;
      a.open_distance_m = c.open.distance_m;
      break;
    case control::CommandKind::kStop:
      a.kind = CommandKind::kStop;
      break;
  }
  return a;
}

}  // namespace tactile::rig
