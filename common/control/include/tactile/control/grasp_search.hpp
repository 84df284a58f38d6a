#pragma once

// The grasp of both phases (Fig. 7's 'Grasping', Fig. 8's grasp): the fingers SEARCH until TOUCH
// on both fingertips, then hold and re-compress (MOVE) for grasp_settle_s, "when the fingers
// have defined a suitable grasp pressure". A fingertip's TOUCH is latched for the search, so a
// force relaxing under F1 does not undo it.
#include <array>
#include <cstdint>

#include "tactile/control/types.hpp"

namespace tactile::control {

// What one update of the grasp brought. TOUCH and the end of the settle come in the same update
// when grasp_settle_s is 0.
struct GraspProgress {
  bool touch = false;  // both fingertips have touched: SEARCH ends (the TOUCH event)
  // grasp_settle_s after the touch, and the grip at its target (or grip_reach_timeout_s more):
  // "grasping ended"
  bool settled = false;
  bool timed_out = false;  // search_timeout_s without TOUCH on both
};

class GraspSearch {
 public:
  GraspSearch(double search_timeout_s, double settle_s, double reach_timeout_s) noexcept
      : search_timeout_s_(search_timeout_s),
        settle_s_(settle_s),
        reach_timeout_s_(reach_timeout_s) {}

  // SEARCH from t, no fingertip touched yet.
  void start(double t) noexcept;
  // No grasp any more: a new step, or the task ended.
  void clear() noexcept { stage_ = Stage::kIdle; }
  // After `settled` or `timed_out` the search is idle again. `grip_ready`: the grip has reached
  // what the grip law asks (always true for the paper's grip): the arm does not move the object
  // before, unless reach_timeout_s past the settle.
  GraspProgress update(const Flags& flags, double t, bool grip_ready = true) noexcept;

  // kSearch while searching, kMove while settling, kOff when idle.
  FingerMode finger_mode() const;

 private:
  enum class Stage : std::uint8_t { kIdle, kSearch, kSettle };

  bool all_touched() const;

  double search_timeout_s_;
  double settle_s_;
  double reach_timeout_s_;
  Stage stage_ = Stage::kIdle;
  double since_s_ = 0;  // the search's or the settle's start
  std::array<bool, kFingertips> touched_{};
};

// The smaller of the fingertips' largest F_z (N): what the grasp holds on its weaker side, the
// value of TOUCH and GRASPING_ENDED.
double grasp_force(const Flags& flags) noexcept;

}  // namespace tactile::control
