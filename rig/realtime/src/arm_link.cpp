#include "tactile/rig/arm_link.hpp"

#include "tactile/rig/scenario_run.hpp"

namespace tactile::rig {

wire::ArmStateData arm_state_of(const World& world, std::int64_t time_ns,
                                std::uint64_t last_command_sequence) {
  // What the lockstep runner's controller sees too (arm_feedback), plus what only the wire has.
  const control::ArmFeedback f = arm_feedback(world);
  wire::ArmStateData s;
  s.time_ns = time_ns;
  s.wrist = f.wrist;
  s.fingertip_position_m = f.fingertip_position_m;
  for (std::size_t i = 0; i < kFingertips; ++i)
    s.fingertip_velocity_mps[i] = world.fingertip(i).velocity_f;
  s.active_segment_id = f.active_segment_id;
  s.segment_done = f.segment_done;
  s.holding = f.holding;
  s.last_command_sequence = last_command_sequence;
  return s;
}

}  // namespace tactile::rig
