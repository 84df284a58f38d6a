#include "tactile/control/segment_runner.hpp"

namespace tactile::control {

Command SegmentRunner::issue(const MoveTo& move, double t, SegmentIds& ids) noexcept {
  active_ = true;
  move_ = move;
  move_.segment_id = ids.take();
  started_s_ = t;
  return Command::move(move_);
}

SegmentStatus SegmentRunner::poll(const ArmFeedback& arm, double t) noexcept {
  if (!active_) return SegmentStatus::kIdle;
  if (arm.active_segment_id == move_.segment_id && arm.segment_done) {
    active_ = false;
    return SegmentStatus::kDone;
  }
  if (t - started_s_ > timeout_s_) {
    active_ = false;
    return SegmentStatus::kTimedOut;
  }
  return SegmentStatus::kRunning;
}

Command SegmentRunner::resume(SegmentIds& ids) noexcept {
  if (!active_) return Command::none();
  move_.segment_id = ids.take();
  return Command::move(move_);
}

}  // namespace tactile::control
