#pragma once

// hand_node's end of the arm link (docs/hand_node.md "The loop", docs/arm.md "Timing"): the
// twin of the arm controller's arm::ArmPeer. When a heartbeat is due, what to send again after
// the arm controller's deadman held the arm, when the arm controller is silent, heard again or
// lost. hand_node moves the bytes and reads the clock; this decides (docs/architecture.md,
// rule 5).
//
// Pure: time is an argument; nothing here reads a clock, touches a socket, logs, allocates or
// throws.
#include <cstdint>
#include <optional>

#include "tactile/control/types.hpp"

namespace tactile::hand {

struct ArmLinkTiming {
  std::int64_t heartbeat_ns = 0;    // heartbeat_period_s: a Heartbeat when nothing went out
  std::int64_t arm_timeout_ns = 0;  // arm_timeout_s: silent this long, warn once
  std::int64_t arm_lost_ns = 0;     // arm_lost_s: silent this long, hold and exit; 0: never
  // A Heartbeat that could not go out (no arm controller connected, or its queue full) is tried
  // again this much later, not at every turn of the loop (0: at every turn).
  std::int64_t retry_ns = 0;
};

class ArmLink {
 public:
  // What an ArmState asks of hand_node, in this order: log the hold, send the resends, log
  // "heard again".
  struct StateHeard {
    bool hold_began = false;   // the first ArmState of a deadman hold (one log line per hold)
    bool heard_again = false;  // the arm controller was reported silent and speaks again
    // What the hold stopped, to send again (the motion first): every ArmState that reports a
    // hold is answered, since a second hold may come before an ArmState without one (the arm
    // reports each hold at least once, docs/arm.md) and a motion sent again is the same segment.
    std::optional<control::Command> motion;      // the last MoveTo
    std::optional<control::Command> velocities;  // the last FingerVelocities
  };

  // What is due at a turn of hand_node's loop.
  struct Due {
    bool heartbeat = false;      // nothing went out for heartbeat_ns: send a Heartbeat
    bool arm_silent = false;     // silent past arm_timeout_ns: warn (once per silence)
    bool arm_lost = false;       // silent past arm_lost_ns: send Hold (naming no frames) and exit
    std::int64_t silent_ns = 0;  // since the arm controller last spoke (once it sent an ArmState)
  };

  explicit ArmLink(const ArmLinkTiming& timing) noexcept : timing_(timing) {}

  // A command was handed to the socket at now_ns; queued false: it could not be (the arm
  // controller is absent) and nothing went out. A MoveTo or FingerVelocities is what the arm
  // does on our word until a Hold, Open or Stop, which leave nothing to resume.
  void command_sent(const control::Command& c, std::int64_t now_ns, bool queued) noexcept;
  // A Heartbeat was handed to the socket at now_ns (queued as above).
  void heartbeat_sent(std::int64_t now_ns, bool queued) noexcept;

  // An ArmState arrived at now_ns; deadman: it carries ARM_FAULT_DEADMAN.
  StateHeard arm_state(bool deadman, std::int64_t now_ns) noexcept;
  // A Heartbeat from the arm controller arrived at now_ns; true: it was reported silent (say it
  // is heard again).
  bool heartbeat_heard(std::int64_t now_ns) noexcept;

  Due due(std::int64_t now_ns) noexcept;
  // When the next Heartbeat is due (hand_node's poll waits no longer); before anything went out,
  // at once: hand_node announces itself. After a send that could not go out, no sooner than
  // retry_ns after it.
  std::int64_t heartbeat_due_ns(std::int64_t now_ns) const noexcept {
    const std::int64_t due = sent_any_ ? last_sent_ns_ + timing_.heartbeat_ns : now_ns;
    return blocked_ && last_blocked_ns_ + timing_.retry_ns > due
               ? last_blocked_ns_ + timing_.retry_ns
               : due;
  }

  // An ArmState came: the arm controller answers (the task may start; silence counts from now).
  bool arm_heard() const noexcept { return arm_heard_; }

 private:
  void sent(std::int64_t now_ns, bool queued) noexcept;
  bool heard(std::int64_t now_ns) noexcept;

  ArmLinkTiming timing_;
  bool sent_any_ = false;
  std::int64_t last_sent_ns_ = 0;
  bool blocked_ = false;  // the last send could not go out
  std::int64_t last_blocked_ns_ = 0;
  bool arm_heard_ = false;
  std::int64_t last_heard_ns_ = 0;
  bool silent_reported_ = false;
  bool in_hold_ = false;  // the last ArmState reported a deadman hold
  std::optional<control::Command> motion_;
  std::optional<control::Command> velocities_;
};

}  // namespace tactile::hand
