#pragma once

// Whether each fingertip's tactile data is fresh enough to act on (docs/hand_node.md "The
// loop"): a fingertip without a whole frame for controller.stale_after_s of hand_node's running
// time is stale (the controller holds), and a fingertip whose frames stopped is not waited for when
// its partner's frame comes (a dead sensor).
//
// Pure: time is an argument, nothing allocates, nothing throws.
#include <array>
#include <cstddef>
#include <cstdint>

namespace tactile::hand {

class TactileFreshness {
 public:
  explicit TactileFreshness(std::int64_t stale_ns) noexcept : stale_ns_(stale_ns) {}

  // A whole frame of fingertip k arrived here at now_ns (a monotonic clock); sent_ns: when it
  // left sensor_node (its receive_timestamp_ns, sensor_node's clock).
  void arrived(std::size_t k, std::int64_t now_ns, std::int64_t sent_ns) noexcept {
    has_frame_[k] = true;
    arrived_ns_[k] = now_ns;
    sent_ns_[k] = sent_ns;
  }

  bool has_frame(std::size_t k) const noexcept { return has_frame_[k]; }

  // hand_node did not run for away_ns (not scheduled, stopped): frames sent meanwhile wait in its
  // socket, so their absence here is no sign the sensor stopped. Staleness counts the time it ran:
  // each fingertip's last arrival moves on by the time it was away.
  void not_running(std::int64_t away_ns) noexcept {
    for (std::size_t k = 0; k < 2; ++k) {
      if (has_frame_[k]) arrived_ns_[k] += away_ns;
    }
  }

  // No whole frame yet, or none for longer than stale_after_s.
  bool stale(std::size_t k, std::int64_t now_ns) const noexcept {
    return !has_frame_[k] || now_ns - arrived_ns_[k] > stale_ns_;
  }

  // Whether fingertip k's frame of an exposure is worth waiting for at now_ns, when the other
  // fingertip's frame that left sensor_node at sent_ns came: its frames came lately here, or its
  // last one left sensor_node shortly before this one. After hand_node was not scheduled for a
  // while, k's next frame is queued behind this one, and not waiting would hold the arm for
  // stale data that is not stale.
  bool live(std::size_t k, std::int64_t now_ns, std::int64_t sent_ns) const noexcept {
    return has_frame_[k] &&
           (now_ns - arrived_ns_[k] <= stale_ns_ || sent_ns_[k] >= sent_ns - stale_ns_);
  }

 private:
  std::int64_t stale_ns_;
  std::array<bool, 2> has_frame_{};
  std::array<std::int64_t, 2> arrived_ns_{};
  std::array<std::int64_t, 2> sent_ns_{};
};

}  // namespace tactile::hand
