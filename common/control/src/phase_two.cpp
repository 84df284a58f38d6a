#include "tactile/control/phase_two.hpp"

#include <algorithm>
#include <cmath>

namespace tactile::control {

void PhaseTwoSequencer::event(EventKind kind, StepOutput& out, const char* text,
                              double value) const {
  Event e;
  e.kind = kind;
  e.phase = phase_;
  e.cycle = cycle_;
  e.text = text;
  e.value = value;
  out.events.push(e);
}

void PhaseTwoSequencer::issue(const char* name, WristPose target, double speed, double yaw_rate,
                              bool keep, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  segment_.active = true;
  segment_.move = MoveTo{ids.take(), name, target, speed, yaw_rate, keep};
  segment_.started_s = in.t;
  out.command = Command::move(segment_.move);
}

bool PhaseTwoSequencer::segment_timed_out(double t) const {
  return segment_.active && t - segment_.started_s > cfg_.segment_timeout_s;
}

void PhaseTwoSequencer::abort(const char* why, StepOutput& out) noexcept {
  event(EventKind::kAborted, out, why);
  phase_ = Phase::kAborted;
  sub_ = Sub::kNone;
  segment_.active = false;
  out.command = Command::stop();
  out.finger_mode = FingerMode::kOff;
}

void PhaseTwoSequencer::start_open(double t, StepOutput& out) noexcept {
  out.command = Command::open_fingers({cfg_.open_speed_mps, cfg_.open_distance_m});
  sub_ = Sub::kOpening;
  sub_started_s_ = t;
}

bool PhaseTwoSequencer::open_complete(double t) const {
  return t - sub_started_s_ >= cfg_.open_distance_m / cfg_.open_speed_mps + cfg_.open_settle_s;
}

void PhaseTwoSequencer::enter(Phase p, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  phase_ = p;
  sub_ = Sub::kNone;
  segment_.active = false;
  event(EventKind::kPhase, out, to_string(p));
  const double sign = cfg_.tighten_clockwise ? -1.0 : 1.0;
  switch (p) {
    case Phase::kTwistApproach:
      issue("TWIST0", reference_, cfg_.move_speed_mps, cfg_.max_yaw_rate_rps, false, in, ids, out);
      break;
    case Phase::kTwistGrasp:
      sub_ = Sub::kSearch;
      sub_started_s_ = in.t;
      touched_.fill(false);
      break;
    case Phase::kTwistTurn: {
      WristPose turned = reference_;
      turned.yaw_rad += sign * cfg_.twist_angle_rad;
      // The fingers keep their velocities: a slip while turning is answered by re-compression.
      issue("TURN", turned, cfg_.move_speed_mps, cfg_.twist_yaw_rate_rps, true, in, ids, out);
      break;
    }
    case Phase::kTwistRelease:
      start_open(in.t, out);
      break;
    case Phase::kTwistReturn:
      issue("RETURN", reference_, cfg_.move_speed_mps, cfg_.twist_yaw_rate_rps, false, in, ids,
            out);
      break;
    case Phase::kTwistFinish:
      if (gave_up_) {
        // The fingers are open and back at the reference already.
        finish(in, ids, out);
      } else {
        // Stop turning at once; the open follows on the next update.
        sub_ = Sub::kHolding;
        out.command = Command::hold();
      }
      break;
    default:
      break;
  }
}

void PhaseTwoSequencer::finish(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  // Straight up with the yaw the wrist has now, kept between the reference and the full turn.
  const double sign = cfg_.tighten_clockwise ? -1.0 : 1.0;
  const double a = reference_.yaw_rad;
  const double b = reference_.yaw_rad + sign * cfg_.twist_angle_rad;
  double yaw = in.arm.wrist.yaw_rad;
  if (!std::isfinite(yaw)) yaw = a;
  yaw = std::clamp(yaw, std::min(a, b), std::max(a, b));
  WristPose up{reference_.position_m, yaw};
  up.position_m.z += cfg_.retract_height_m;
  sub_ = Sub::kRetreat;
  issue("RETREAT", up, cfg_.move_speed_mps, cfg_.max_yaw_rate_rps, false, in, ids, out);
}

void PhaseTwoSequencer::begin_cycle(const StepInput& in, SegmentIds& ids,
                                    StepOutput& out) noexcept {
  ++cycle_;
  cycle_slips_ = 0;
  event(EventKind::kTwistCycle, out, "twist cycle", static_cast<double>(cycle_));
  enter(Phase::kTwistGrasp, in, ids, out);
}

void PhaseTwoSequencer::start(const WristPose& reference, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  reference_ = reference;
  cycle_ = 0;
  cycle_slips_ = 0;
  previous_cycle_slipped_ = false;
  tight_cycle_ = 0;
  gave_up_ = false;
  finished_ = false;
  enter(Phase::kTwistApproach, in, ids, out);
  out.finger_mode = FingerMode::kOff;
}

void PhaseTwoSequencer::step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  const double t = in.t;
  switch (phase_) {
    case Phase::kTwistApproach:
      if (segment_.done(in.arm)) {
        begin_cycle(in, ids, out);
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;

    case Phase::kTwistGrasp:
      if (sub_ == Sub::kSearch) {
        for (std::size_t f = 0; f < kFingertips; ++f) {
          touched_[f] = touched_[f] || in.flags.fingertip[f].touch;
        }
        if (touched_[0] && touched_[1]) {
          event(EventKind::kTouch, out, "both fingertips touch",
                std::min(in.flags.fingertip[0].max_fz_n, in.flags.fingertip[1].max_fz_n));
          sub_ = Sub::kSettle;
          sub_started_s_ = t;
        } else if (t - sub_started_s_ > cfg_.search_timeout_s) {
          abort("search timed out before both fingertips touched", out);
          break;
        }
      }
      if (sub_ == Sub::kSettle && t - sub_started_s_ >= cfg_.grasp_settle_s) {
        enter(Phase::kTwistTurn, in, ids, out);
      }
      break;

    case Phase::kTwistTurn: {
      // A detection is one fresh frame of one fingertip with SLIP raised (docs/control.md).
      for (std::size_t f = 0; f < kFingertips; ++f) {
        if (in.flags.fingertip[f].slip) ++cycle_slips_;
      }
      const char* why = nullptr;
      if (cycle_slips_ >= cfg_.ns) {
        why = "Ns slip detections in one cycle";
      } else if (previous_cycle_slipped_ && cycle_slips_ >= cfg_.cycle_slip_min) {
        why = "slip detected in two consecutive cycles";
      }
      if (why != nullptr) {
        tight_cycle_ = cycle_;
        event(EventKind::kCapTight, out, why, static_cast<double>(cycle_slips_));
        enter(Phase::kTwistFinish, in, ids, out);
      } else if (segment_.done(in.arm)) {
        enter(Phase::kTwistRelease, in, ids, out);
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;
    }

    case Phase::kTwistRelease:
      if (open_complete(t)) enter(Phase::kTwistReturn, in, ids, out);
      break;

    case Phase::kTwistReturn:
      if (segment_.done(in.arm)) {
        previous_cycle_slipped_ = cycle_slips_ >= cfg_.cycle_slip_min;
        if (cycle_ >= cfg_.max_twist_cycles) {
          gave_up_ = true;
          enter(Phase::kTwistFinish, in, ids, out);
        } else {
          begin_cycle(in, ids, out);
        }
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;

    case Phase::kTwistFinish:
      if (sub_ == Sub::kHolding) {
        start_open(t, out);
      } else if (sub_ == Sub::kOpening) {
        if (open_complete(t)) finish(in, ids, out);
      } else if (sub_ == Sub::kRetreat) {
        if (segment_.done(in.arm)) {
          segment_.active = false;
          if (gave_up_) {
            abort("no tightness detected within max_twist_cycles", out);
          } else {
            finished_ = true;
          }
        } else if (segment_timed_out(t)) {
          abort("segment timed out", out);
        }
      }
      break;

    default:
      break;
  }

  switch (phase_) {
    case Phase::kTwistGrasp:
      out.finger_mode = sub_ == Sub::kSearch ? FingerMode::kSearch : FingerMode::kMove;
      break;
    case Phase::kTwistTurn:
      out.finger_mode = FingerMode::kMove;
      break;
    default:
      out.finger_mode = FingerMode::kOff;
      break;
  }
}

Command PhaseTwoSequencer::resume(SegmentIds& ids, double t) noexcept {
  if (sub_ == Sub::kOpening) {
    // The open's timer goes on from where the hold stopped it.
    return resume_open(cfg_, t - sub_started_s_);
  }
  if (segment_.active && !finished_) {
    segment_.move.segment_id = ids.take();
    return Command::move(segment_.move);
  }
  return Command::none();
}

}  // namespace tactile::control
