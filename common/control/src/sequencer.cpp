#include "tactile/control/sequencer.hpp"

#include <algorithm>
#include <cmath>

namespace tactile::control {

void Sequencer::clear() noexcept {
  segment_.clear();
  grasp_.clear();
  release_.clear();
}

void Sequencer::restart() noexcept {
  phase_ = Phase::kIdle;
  cycle_ = 0;
  clear();
}

void Sequencer::enter(Phase p, StepOutput& out) noexcept {
  phase_ = p;
  clear();
  event(EventKind::kPhase, out, to_string(p));
}

void Sequencer::finish() noexcept {
  phase_ = Phase::kDone;
  clear();
}

void Sequencer::abort(const char* why, StepOutput& out) noexcept {
  event(EventKind::kAborted, out, why);
  phase_ = Phase::kAborted;
  clear();
  out.command = Command::stop();
  out.finger_mode = FingerMode::kOff;
}

void Sequencer::event(Event e, StepOutput& out) const {
  e.phase = phase_;
  e.cycle = cycle_;
  out.events.push(e);
}

void Sequencer::event(EventKind kind, StepOutput& out, const char* text, double value) const {
  Event e;
  e.kind = kind;
  e.text = text;
  e.value = value;
  event(e, out);
}

void Sequencer::move(const MoveTo& move, double t, SegmentIds& ids, StepOutput& out) noexcept {
  out.command = segment_.issue(move, t, ids);
}

bool Sequencer::segment_done(const StepInput& in, StepOutput& out) noexcept {
  switch (segment_.poll(in.arm, in.t)) {
    case SegmentStatus::kDone:
      return true;
    case SegmentStatus::kTimedOut:
      abort("segment timed out", out);
      return false;
    case SegmentStatus::kIdle:
    case SegmentStatus::kRunning:
      break;
  }
  return false;
}

bool Sequencer::grasp_settled(const StepInput& in, StepOutput& out) noexcept {
  const GraspProgress p = grasp_.update(in.flags, in.t, in.grip_ready);
  if (p.touch) event(EventKind::kTouch, out, "both fingertips touch", grasp_force(in.flags));
  if (p.timed_out) abort("search timed out before both fingertips touched", out);
  return p.settled;
}

FingerMode Sequencer::finger_mode() const {
  const FingerMode grasping = grasp_.finger_mode();
  if (grasping != FingerMode::kOff) return grasping;
  return segment_.carries_object() ? FingerMode::kMove : FingerMode::kOff;
}

bool Sequencer::accelerates_within(const ArmFeedback& arm, double t, double lead_s) const noexcept {
  if (grasp_.finger_mode() == FingerMode::kMove) return true;
  if (!segment_.carries_object()) return false;
  if (t - segment_.started_s() < lead_s) return true;
  const MoveTo& m = segment_.move();
  const double distance_m = norm(m.target.position_m - arm.wrist.position_m);
  const double turn_rad = std::abs(m.target.yaw_rad - arm.wrist.yaw_rad);
  const double left_s = std::max(distance_m / m.max_speed_mps, turn_rad / m.max_yaw_rate_rps);
  // A pose that is not finite says nothing of the time left: more grip, not less.
  return !(left_s > lead_s);
}

Command Sequencer::resume(SegmentIds& ids, double t) noexcept {
  const Command open = release_.resume(t);
  if (open.kind != CommandKind::kNone) return open;
  return segment_.resume(ids);
}

}  // namespace tactile::control
