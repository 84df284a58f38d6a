#pragma once

// When hand_node runs the controller on arriving frames (docs/hand_node.md "The loop").
//
// The two fingertips' cameras expose together (the rig's cameras share their frame instants;
// a lab triggers its cameras together), but their frames reach hand_node one after the other.
// Running the controller on the first would answer it with the other fingertip's frame of the
// exposure before, a whole period old. So a frame waits, at most `window`, for the other
// fingertip's frame stamped within `window` of its own; the controller then runs once with both
// marked fresh, as in the lockstep rig. A window of 0 runs it on every frame as it comes.
//
// The stamp is sensor_node's receive time of the frame, not the camera's timestamp: cameras
// triggered together need not share a clock, the host that receives them has one.
//
// Pure: time is an argument, nothing allocates, nothing throws.
#include <array>
#include <cstdint>

namespace tactile::hand {

class FramePairing {
 public:
  using Fresh = std::array<bool, 2>;

  explicit FramePairing(std::int64_t window_ns) noexcept : window_ns_(window_ns) {}

  // True when fingertip k already has a frame waiting: run the controller on it (take()) before
  // its next frame replaces it.
  bool waiting(int k) const noexcept { return pending_[index(k)]; }

  // A whole frame of fingertip k, stamped stamp_ns, arrived at now_ns (a monotonic clock).
  // other_live: the other fingertip is neither stale nor without a frame yet (a dead sensor is
  // not waited for). Returns true when the controller should run now on take().
  bool arrived(int k, std::int64_t stamp_ns, std::int64_t now_ns, bool other_live) noexcept {
    const std::size_t i = index(k);
    const std::size_t j = 1 - i;
    pending_[i] = true;
    last_ts_[i] = stamp_ns;
    has_ts_[i] = true;
    if (window_ns_ <= 0 || !other_live || pending_[j]) return true;
    // The other fingertip's frame of this exposure came already, or it is ahead of this one.
    if (has_ts_[j] && last_ts_[j] >= stamp_ns - window_ns_) return true;
    deadline_ns_ = now_ns + window_ns_;
    return false;
  }

  bool any_waiting() const noexcept { return pending_[0] || pending_[1]; }
  std::int64_t deadline_ns() const noexcept { return deadline_ns_; }
  // A frame waited the whole window and its partner did not come (lost, incomplete, late).
  bool due(std::int64_t now_ns) const noexcept { return any_waiting() && now_ns >= deadline_ns_; }

  // The fingertips whose frames the controller has not yet run on; clears them.
  Fresh take() noexcept {
    const Fresh f = pending_;
    pending_ = {};
    return f;
  }

 private:
  static std::size_t index(int k) noexcept { return k == 0 ? 0 : 1; }

  std::int64_t window_ns_;
  Fresh pending_{};
  std::array<std::int64_t, 2> last_ts_{};
  std::array<bool, 2> has_ts_{};
  std::int64_t deadline_ns_ = 0;
};

}  // namespace tactile::hand
