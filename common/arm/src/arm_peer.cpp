#include "tactile/arm/arm_peer.hpp"

namespace tactile::arm {

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
  unreported_ = true;
  return true;
}

}  // namespace tactile::arm
