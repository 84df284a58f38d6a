#pragma once

// Who the arm answers and the deadman that holds the arm when that client falls silent
// (docs/arm.md, "Timing"). Pure: time is an argument, nothing here reads a clock or touches a
// socket.
#include <cstdint>
#include <string>
#include <string_view>

namespace tactile::arm {

// The client the arm answers (its peer) and the deadman that holds the arm when that client
// falls silent. The peer is the first client that spoke (a heartbeat) or the last that sent a
// valid command; garbage never changes it, and only its words keep the deadman from tripping.
// The hold lasts until a client commands again (its ArmStates carry the fault meanwhile, and at
// least once).
class ArmPeer {
 public:
  // What a message changed, for the log.
  struct Heard {
    bool accepted = false;    // false: refused (another client's heartbeat while ours is alive)
    bool connected = false;   // the first client
    bool new_client = false;  // another client than the peer: it takes over
    bool resumed = false;     // a command after the deadman hold: the hold ends
  };

  explicit ArmPeer(std::int64_t deadman_ns) : deadman_ns_(deadman_ns) {}

  // A heartbeat from `from` at `now_ns`. Another client's heartbeat takes over only while the
  // arm is held for the old peer's silence (a restarted hand_node).
  Heard heartbeat(std::string_view from, std::int64_t now_ns);
  // A valid command from `from` at `now_ns`: its sender becomes the peer.
  Heard command(std::string_view from, std::int64_t now_ns);
  // True once, at the first `now_ns` the peer has been silent longer than the deadman: hold the
  // arm now. Never before a peer spoke.
  bool deadman_trips(std::int64_t now_ns);

  bool has_peer() const { return has_peer_; }
  const std::string& peer() const { return peer_; }
  // The arm is held for the peer's silence.
  bool held() const { return held_; }
  // What the next ArmState says (ARM_FAULT_DEADMAN): the arm is held, or was held since the last
  // ArmState. A hold ends at the peer's next command, which may come before any ArmState reported
  // it (a velocity command sent meanwhile); the client must still learn that the hold stopped its
  // motion, so the report is latched until one ArmState has carried it.
  bool report_deadman() {
    const bool report = held_ || unreported_;
    unreported_ = false;
    return report;
  }
  std::int64_t last_heard_ns() const { return last_heard_ns_; }
  std::int64_t deadman_ns() const { return deadman_ns_; }

 private:
  void heard(std::string_view from, std::int64_t now_ns);

  std::int64_t deadman_ns_;
  std::string peer_;
  bool has_peer_ = false;
  bool held_ = false;
  bool unreported_ = false;  // a hold no ArmState has reported yet
  std::int64_t last_heard_ns_ = 0;
};

}  // namespace tactile::arm
