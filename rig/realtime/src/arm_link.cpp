#include "tactile/rig/arm_link.hpp"

namespace tactile::rig {

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
