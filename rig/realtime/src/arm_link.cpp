#include "tactile/rig/arm_link.hpp"

namespace tactile::rig {

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

wire::ArmStateData arm_state_of(const World& world, std::int64_t time_ns,
                                std::uint64_t last_command_sequence) {
  wire::ArmStateData s;
  const rig::ArmState& arm = world.arm();
  s.time_ns = time_ns;
  s.wrist = {arm.position_m, arm.yaw_rad};
  for (std::size_t i = 0; i < kFingertips; ++i) {
    s.fingertip_position_m[i] = world.fingertip(i).offset_w;
    s.fingertip_velocity_mps[i] = world.fingertip(i).velocity_f;
  }
  s.active_segment_id = arm.active_segment_id;
  s.segment_done = arm.segment_done;
  s.holding = arm.holding || arm.stopped;
  s.last_command_sequence = last_command_sequence;
  return s;
}

}  // namespace tactile::rig
