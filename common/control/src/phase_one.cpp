#include "tactile/control/phase_one.hpp"

#include <algorithm>
#include <cmath>

namespace tactile::control {

namespace {

double smaller_grip(const Flags& flags) {
  return std::min(flags.fingertip[0].max_fz_n, flags.fingertip[1].max_fz_n);
}

Event classified(EventKind kind, Phase phase, const SlipDirection& d) {
  Event e;
  e.kind = kind;
  e.phase = phase;
  e.fingertip = d.fingertip;
  e.has_element = d.index != kNoElement;
  e.element_id = d.element_id;
  e.value = d.along_gravity_mm;
  e.text = kind == EventKind::kGraspClassified ? "positive slip along gravity"
                                               : "negative slip along gravity";
  return e;
}

}  // namespace

WristPose PhaseOneSequencer::place(double x, double y, double z) const {
  return {{x, y, z}, cfg_.grasp_yaw_rad};
}

void PhaseOneSequencer::event(EventKind kind, StepOutput& out, const char* text,
                              double value) const {
  Event e;
  e.kind = kind;
  e.phase = phase_;
  e.text = text;
  e.value = value;
  out.events.push(e);
}

void PhaseOneSequencer::issue(const char* name, WristPose target, double speed, double yaw_rate,
                              bool keep, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  segment_.active = true;
  segment_.move = MoveTo{ids.take(), name, target, speed, yaw_rate, keep};
  segment_.started_s = in.t;
  out.command = Command::move(segment_.move);
}

bool PhaseOneSequencer::segment_timed_out(double t) const {
  return segment_.active && t - segment_.started_s > cfg_.segment_timeout_s;
}

void PhaseOneSequencer::abort(const char* why, StepOutput& out) noexcept {
  event(EventKind::kAborted, out, why);
  phase_ = Phase::kAborted;
  sub_ = Sub::kNone;
  segment_.active = false;
  out.command = Command::stop();
  out.finger_mode = FingerMode::kOff;
}

void PhaseOneSequencer::enter(Phase p, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  phase_ = p;
  sub_ = Sub::kNone;
  segment_.active = false;
  event(EventKind::kPhase, out, to_string(p));
  switch (p) {
    case Phase::kApproach:
      issue("MOVE1", place(cfg_.cap_x_m, cfg_.cap_y_m, cfg_.safe_height_m), cfg_.move_speed_mps,
            cfg_.max_yaw_rate_rps, false, in, ids, out);
      break;
    case Phase::kDescend:
      issue("MOVE2", place(cfg_.cap_x_m, cfg_.cap_y_m, cfg_.grasp_height_m), cfg_.move_speed_mps,
            cfg_.max_yaw_rate_rps, false, in, ids, out);
      break;
    case Phase::kGrasp:
      sub_ = Sub::kSearch;
      sub_started_s_ = in.t;
      touched_.fill(false);
      break;
    case Phase::kLift:
      // The fingers keep their velocities: a slip on lift is answered while the arm moves.
      issue("MOVE3", place(cfg_.cap_x_m, cfg_.cap_y_m, cfg_.carry_height_m), cfg_.lift_speed_mps,
            cfg_.max_yaw_rate_rps, true, in, ids, out);
      break;
    case Phase::kTransport:
      issue("MOVE4", place(cfg_.bottle_x_m, cfg_.bottle_y_m, cfg_.carry_height_m),
            cfg_.carry_speed_mps, cfg_.max_yaw_rate_rps, true, in, ids, out);
      break;
    case Phase::kLower:
      issue("MOVE5", place(cfg_.bottle_x_m, cfg_.bottle_y_m, cfg_.lower_limit_m),
            cfg_.lower_speed_mps, cfg_.max_yaw_rate_rps, true, in, ids, out);
      break;
    case Phase::kRelease:
      // Stop the arm where the contact was felt; the open follows on the next update.
      sub_ = Sub::kHolding;
      out.command = Command::hold();
      break;
    case Phase::kRetract: {
      // The release happened above the bottle; only its height was unknown. Keep that height
      // inside the range MOVE5 covered, whatever the feedback says.
      double z = in.arm.wrist.position_m.z;
      if (!std::isfinite(z)) z = cfg_.carry_height_m;
      z = std::clamp(z, cfg_.lower_limit_m, cfg_.carry_height_m);
      release_pose_ = place(cfg_.bottle_x_m, cfg_.bottle_y_m, z);
      WristPose up = release_pose_;
      up.position_m.z += cfg_.retract_height_m;
      issue("MOVE6", up, cfg_.move_speed_mps, cfg_.max_yaw_rate_rps, false, in, ids, out);
      break;
    }
    default:
      break;
  }
}

void PhaseOneSequencer::start(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  finished_ = false;
  grasp_classified_ = false;
  released_on_lift_ = false;
  settled_after_s_ = 0;
  enter(Phase::kApproach, in, ids, out);
  out.finger_mode = FingerMode::kOff;
}

void PhaseOneSequencer::step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  const double t = in.t;
  // A deadman hold of the arm controller (nothing heard from us for a while) stops the lift or
  // the lowering, and the restart hand_node then sends starts it again under the cap: the slips
  // of the stop and the start are its inertia, not its weight or a support. As after a stale
  // hold, no slip direction is classified while the deadman holds nor for resume_settle_s
  // after. Only the deadman: the feedback's `holding` also reports our own Holds, and for a
  // frame after the next motion was sent.
  if (in.arm.deadman && (phase_ == Phase::kLift || phase_ == Phase::kLower))
    settled_after_s_ = std::max(settled_after_s_, t + cfg_.resume_settle_s);
  switch (phase_) {
    case Phase::kApproach:
    case Phase::kDescend:
    case Phase::kTransport:
      if (segment_.done(in.arm)) {
        enter(phase_ == Phase::kApproach  ? Phase::kDescend
              : phase_ == Phase::kDescend ? Phase::kGrasp
                                          : Phase::kLower,
              in, ids, out);
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;

    case Phase::kGrasp:
      if (sub_ == Sub::kSearch) {
        for (std::size_t f = 0; f < kFingertips; ++f) {
          touched_[f] = touched_[f] || in.flags.fingertip[f].touch;
        }
        if (touched_[0] && touched_[1]) {
          event(EventKind::kTouch, out, "both fingertips touch", smaller_grip(in.flags));
          sub_ = Sub::kSettle;
          sub_started_s_ = t;
        } else if (t - sub_started_s_ > cfg_.search_timeout_s) {
          abort("search timed out before both fingertips touched", out);
          break;
        }
      }
      if (sub_ == Sub::kSettle && t - sub_started_s_ >= cfg_.grasp_settle_s) {
        event(EventKind::kGraspingEnded, out, "grasp pressure set", smaller_grip(in.flags));
        enter(Phase::kLift, in, ids, out);
      }
      break;

    case Phase::kLift: {
      if (!grasp_classified_ && t >= settled_after_s_) {
        const SlipDirection d = analyze_slip_direction(in.fingertips, in.flags, cfg_.gravity_axis,
                                                       cfg_.direction_deadband_mm);
        if (d.classification == SlipClass::kGrasp) {
          // The weight pulls the cap along gravity: it is held; keep lifting.
          out.events.push(classified(EventKind::kGraspClassified, phase_, d));
          grasp_classified_ = true;
        } else if (d.classification == SlipClass::kRelease) {
          // Pushed against gravity while lifting: something still holds the cap from below.
          // The paper's rule says release: put it back and end the task.
          released_on_lift_ = true;
          enter(Phase::kRelease, in, ids, out);
          break;
        }
      }
      if (segment_.done(in.arm)) {
        enter(Phase::kTransport, in, ids, out);
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;
    }

    case Phase::kLower: {
      // Positive slips here (deceleration, vibration) are the estimator's: re-compression. The
      // first negative one is the cap meeting the bottle or the ground.
      const SlipDirection d =
          t >= settled_after_s_ ? analyze_slip_direction(in.fingertips, in.flags, cfg_.gravity_axis,
                                                         cfg_.direction_deadband_mm)
                                : SlipDirection{};
      if (d.classification == SlipClass::kRelease) {
        out.events.push(classified(EventKind::kReleaseClassified, phase_, d));
        enter(Phase::kRelease, in, ids, out);
      } else if (segment_.done(in.arm)) {
        abort("lowered to lower_limit_m without a negative slip", out);
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;
    }

    case Phase::kRelease:
      if (sub_ == Sub::kHolding) {
        out.command = Command::open_fingers({cfg_.open_speed_mps, cfg_.open_distance_m});
        sub_ = Sub::kOpening;
        sub_started_s_ = t;
      } else if (t - sub_started_s_ >=
                 cfg_.open_distance_m / cfg_.open_speed_mps + cfg_.open_settle_s) {
        enter(Phase::kRetract, in, ids, out);
      }
      break;

    case Phase::kRetract:
      if (segment_.done(in.arm)) {
        segment_.active = false;
        if (released_on_lift_) {
          abort("negative slip on lift: the cap was put back", out);
        } else {
          finished_ = true;
        }
      } else if (segment_timed_out(t)) {
        abort("segment timed out", out);
      }
      break;

    default:
      break;
  }

  switch (phase_) {
    case Phase::kGrasp:
      out.finger_mode = sub_ == Sub::kSearch ? FingerMode::kSearch : FingerMode::kMove;
      break;
    case Phase::kLift:
    case Phase::kTransport:
    case Phase::kLower:
      out.finger_mode = FingerMode::kMove;
      break;
    default:
      out.finger_mode = FingerMode::kOff;
      break;
  }
}

Command PhaseOneSequencer::resume(SegmentIds& ids, double t) noexcept {
  if (phase_ == Phase::kRelease && sub_ == Sub::kOpening) {
    // The open's timer goes on from where the hold stopped it.
    return resume_open(cfg_, t - sub_started_s_);
  }
  if (segment_.active && !finished_) {
    // The hold interrupted the segment: run it again under a new id, so that a done flag of the
    // old one cannot be mistaken for the new one's.
    settled_after_s_ = t + cfg_.resume_settle_s;
    segment_.move.segment_id = ids.take();
    return Command::move(segment_.move);
  }
  return Command::none();
}

}  // namespace tactile::control
