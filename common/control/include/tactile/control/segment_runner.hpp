#pragma once

// One motion trajectory command at a time (the paper's MOVE1..MOVE6, Phase II's TWIST0, TURN,
// RETURN, RETREAT): issued under a fresh id, done when the arm reports that id done, timed out
// after segment_timeout_s, sent again under a new id after a hold stopped it.
#include <cstdint>

#include "tactile/control/types.hpp"

namespace tactile::control {

// Segment ids handed out by the controller, shared by both sequencers so that an id is never
// reused within a task (the arm reports the id of the segment it is running).
class SegmentIds {
 public:
  std::uint32_t take() noexcept { return next_++; }

 private:
  std::uint32_t next_ = 1;
};

enum class SegmentStatus : std::uint8_t {
  kIdle,      // no segment
  kRunning,   // issued, not done yet
  kDone,      // the arm reports it done; the runner is idle again
  kTimedOut,  // not done within the timeout; the runner is idle again
};

class SegmentRunner {
 public:
  explicit SegmentRunner(double timeout_s) noexcept : timeout_s_(timeout_s) {}

  // The command that sends `move` under a new id (its own segment_id is ignored); its timeout
  // runs from t.
  Command issue(const MoveTo& move, double t, SegmentIds& ids) noexcept;
  // No segment any more: a new step, or the task ended.
  void clear() noexcept { active_ = false; }
  SegmentStatus poll(const ArmFeedback& arm, double t) noexcept;
  // After a hold stopped the arm: the unfinished segment again under a new id, so that a done
  // flag of the old one cannot be mistaken for the new one's (its timeout runs on). kNone when no
  // segment runs.
  Command resume(SegmentIds& ids) noexcept;

  bool active() const { return active_; }
  // A segment runs that keeps the finger velocities: the arm carries the object and the fingers
  // answer its slips on the way.
  bool carries_object() const { return active_ && move_.keep_finger_velocities; }
  const MoveTo& move() const { return move_; }
  // When the segment was issued (a resume keeps it, as it keeps the timeout).
  double started_s() const { return started_s_; }

 private:
  double timeout_s_;
  bool active_ = false;
  MoveTo move_;
  double started_s_ = 0;
};

}  // namespace tactile::control
