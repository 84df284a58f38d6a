#include "arm_link.hpp"

namespace tactile::hand {

void ArmLink::sent(std::int64_t now_ns, bool queued) noexcept {
  // Only what went out keeps the arm controller's deadman from tripping.
  blocked_ = !queued;
  if (!queued) {
    last_blocked_ns_ = now_ns;
    return;
  }
  sent_any_ = true;
  last_sent_ns_ = now_ns;
}

void ArmLink::command_sent(const control::Command& c, std::int64_t now_ns, bool queued) noexcept {
  switch (c.kind) {
    case control::CommandKind::kMoveTo:
      motion_ = c;
      break;
    case control::CommandKind::kFingerVelocities:
      velocities_ = c;
      break;
    case control::CommandKind::kHold:
    case control::CommandKind::kOpen:
    case control::CommandKind::kStop:
      motion_.reset();
      velocities_.reset();
      break;
    case control::CommandKind::kNone:
      break;
  }
  sent(now_ns, queued);
}

void ArmLink::heartbeat_sent(std::int64_t now_ns, bool queued) noexcept {
  sent(now_ns, queued);
}

bool ArmLink::heard(std::int64_t now_ns) noexcept {
  last_heard_ns_ = now_ns;
  const bool again = silent_reported_;
  silent_reported_ = false;
  return again;
}

ArmLink::StateHeard ArmLink::arm_state(bool deadman, std::int64_t now_ns) noexcept {
  StateHeard h;
  arm_heard_ = true;
  if (deadman) {
    // The arm held because it heard nothing from us for a while (we were not scheduled, or the
    // link stalled). We are here: carry on with what the arm was doing.
    h.hold_began = !in_hold_;
    h.motion = motion_;
    h.velocities = velocities_;
  }
  in_hold_ = deadman;
  h.heard_again = heard(now_ns);
  return h;
}

bool ArmLink::heartbeat_heard(std::int64_t now_ns) noexcept {
  return heard(now_ns);
}

ArmLink::Due ArmLink::due(std::int64_t now_ns) noexcept {
  Due d;
  d.heartbeat = now_ns >= heartbeat_due_ns(now_ns);
  if (!arm_heard_) return d;  // before the arm controller first answers, wait however long
  d.silent_ns = now_ns - last_heard_ns_;
  if (!silent_reported_ && d.silent_ns > timing_.arm_timeout_ns) {
    d.arm_silent = true;
    silent_reported_ = true;
  }
  // Gone, not slow: hand_node holds (should it come back, the arm stays where it is) and gives up.
  d.arm_lost = timing_.arm_lost_ns > 0 && d.silent_ns > timing_.arm_lost_ns;
  return d;
}

}  // namespace tactile::hand
