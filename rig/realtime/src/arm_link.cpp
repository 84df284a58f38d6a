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

namespace tactile::rig {

void ArmPeer::heard(std::string_view from, std::int64_t now_ns) {
  peer_.assign(from);
  has_peer_ = true;
  last_heard_ns_ = now_ns;
}

ArmPeer::Heard ArmPeer::heartbeat(std::string_view from, std::int64_t now_ns) {
  Heard h;
  h.connected = !has_peer_;
  h.new_client = has_peer_ && from != peer_;
  if (h.new_client && !held_) return h;  // ours is alive: refused
  h.accepted = true;
  heard(from, now_ns);
  return h;
}

ArmPeer::Heard ArmPeer::command(std::string_view from, std::int64_t now_ns) {
  Heard h;
  h.accepted = true;
  h.connected = !has_peer_;
  h.new_client = has_peer_ && from != peer_;
  h.resumed = held_;
  held_ = false;
  heard(from, now_ns);
  return h;
}

bool ArmPeer::deadman_trips(std::int64_t now_ns) {
  if (!has_peer_ || held_ || now_ns - last_heard_ns_ <= deadman_ns_) return false;
  held_ = true;
  return true;
}

}  // namespace tactile::rig
