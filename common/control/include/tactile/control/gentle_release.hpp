#pragma once

// The release of both phases ("the robot hands will gently release the object"): optionally a
// Hold first, so that the arm stops where the contact was felt, then Open at open_speed_mps over
// open_distance_m, done after its nominal duration and open_settle_s. The open's timer runs on
// task time, which stale holds do not advance.
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

class GentleRelease {
 public:
  explicit GentleRelease(const Config& cfg) noexcept
      : speed_mps_(cfg.open_speed_mps),
        distance_m_(cfg.open_distance_m),
        settle_s_(cfg.open_settle_s) {}

  // Hold now; the open follows on the next update().
  Command hold() noexcept;
  // Open now, from t.
  Command open(double t) noexcept;
  // No release any more: a new step, or the task ended.
  void clear() noexcept { stage_ = Stage::kIdle; }
  // One update: after a hold, sends the open (into `command`); true once, when the open has run
  // its course. Idle again after that.
  bool update(double t, Command& command) noexcept;
  // The open that carries on after a stale hold stopped it: only the distance it had left, so
  // that holds never add up to a wider open (its timer goes on). kNone when it is not opening or
  // had finished its stroke.
  Command resume(double t) const noexcept;

 private:
  enum class Stage : std::uint8_t { kIdle, kHolding, kOpening };

  double speed_mps_;
  double distance_m_;
  double settle_s_;
  Stage stage_ = Stage::kIdle;
  double opened_s_ = 0;
};

}  // namespace tactile::control
