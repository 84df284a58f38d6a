#include "tactile/control/phase_one.hpp"

#include <algorithm>
#include <cmath>

namespace tactile::control {

namespace {

Event classified(EventKind kind, const SlipDirection& d) {
  Event e;
  e.kind = kind;
  e.fingertip = d.fingertip;
  e.has_element = d.index != kNoElement;
  e.element_id = d.element_id;
  e.value = d.along_gravity_mm;
  e.text = kind == EventKind::kGraspClassified ? "positive slip along gravity"
                                               : "negative slip along gravity";
  return e;
}

}  // namespace

WristPose PhaseOneSequencer::above_cap(double z) const {
  return {{cfg_.cap_x_m, cfg_.cap_y_m, z}, cfg_.grasp_yaw_rad};
}

WristPose PhaseOneSequencer::above_bottle(double z) const {
  return {{cfg_.bottle_x_m, cfg_.bottle_y_m, z}, cfg_.grasp_yaw_rad};
}

MoveTo PhaseOneSequencer::travel(const char* name, WristPose target, double speed) const {
  return MoveTo{0, name, target, speed, cfg_.max_yaw_rate_rps, false};
}

// The fingers keep their velocities: a slip is answered while the arm carries the cap.
MoveTo PhaseOneSequencer::carry(const char* name, WristPose target, double speed) const {
  return MoveTo{0, name, target, speed, cfg_.max_yaw_rate_rps, true};
}

// The release happened above the bottle; only its height was unknown. Keep that height inside
// the range MOVE5 covered, whatever the feedback says.
WristPose PhaseOneSequencer::released_at(const ArmFeedback& arm) const {
  double z = arm.wrist.position_m.z;
  if (!std::isfinite(z)) z = cfg_.carry_height_m;
  return above_bottle(std::clamp(z, cfg_.lower_limit_m, cfg_.carry_height_m));
}

void PhaseOneSequencer::enter(Phase p, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  seq_.enter(p, out);
  const double t = in.t;
  switch (p) {
    case Phase::kApproach:
      seq_.move(travel("MOVE1", above_cap(cfg_.safe_height_m), cfg_.move_speed_mps), t, ids, out);
      break;
    case Phase::kDescend:
      seq_.move(travel("MOVE2", above_cap(cfg_.grasp_height_m), cfg_.move_speed_mps), t, ids, out);
      break;
    case Phase::kGrasp:
      seq_.search(t);
      break;
    case Phase::kLift:
      lift_base_n_ = load();
      loading_ = lift_loads_first(cfg_);
      if (loading_) {
        // The loading phase: the grip follows the weight arriving before the cap leaves.
        seq_.move(carry("MOVE3", above_cap(cfg_.grasp_height_m + cfg_.grip_loading_distance_m),
                        cfg_.grip_loading_speed_mps),
                  t, ids, out);
      } else {
        begin_lift(t, ids, out);
      }
      break;
    case Phase::kTransport:
      seq_.move(carry("MOVE4", above_bottle(cfg_.carry_height_m), cfg_.carry_speed_mps), t, ids,
                out);
      break;
    case Phase::kLower:
      lower_base_n_ = load();
      carried_n_ = lower_base_n_ - lift_base_n_;
      lower_below_ = 0;
      seq_.move(carry("MOVE5", above_bottle(cfg_.lower_limit_m), cfg_.lower_speed_mps), t, ids,
                out);
      break;
    case Phase::kRelease:
      // Stop the arm where the contact was felt.
      seq_.hold_then_open(out);
      break;
    case Phase::kRetract: {
      release_pose_ = released_at(in.arm);
      WristPose up = release_pose_;
      up.position_m.z += cfg_.retract_height_m;
      seq_.move(travel("MOVE6", up, cfg_.move_speed_mps), t, ids, out);
      break;
    }
    default:
      break;
  }
}

void PhaseOneSequencer::begin_lift(double t, SegmentIds& ids, StepOutput& out) noexcept {
  lift_start_s_ = t;
  lift_frames_ = lift_slip_frames_ = 0;
  lift_gain_sum_n_ = 0;
  seq_.move(carry("MOVE3", above_cap(cfg_.carry_height_m), cfg_.lift_speed_mps), t, ids, out);
}

void PhaseOneSequencer::start(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  grasp_classified_ = false;
  released_on_lift_ = false;
  loading_ = false;
  settled_after_s_ = 0;
  seq_.restart();
  enter(Phase::kApproach, in, ids, out);
  out.finger_mode = seq_.finger_mode();
}

// A deadman hold of the arm controller (nothing heard from us for a while) stops the lift or the
// lowering, and the restart hand_node then sends starts it again under the cap: the slips of the
// stop and the start are its inertia, not its weight or a support. As after a stale hold, no
// slip direction is classified while the deadman holds nor for resume_settle_s after. Only the
// deadman: the feedback's `holding` also reports our own Holds, and for a frame after the next
// motion was sent.
void PhaseOneSequencer::defer_classification_on_deadman(const StepInput& in) noexcept {
  const Phase p = seq_.phase();
  if (in.arm.deadman && (p == Phase::kLift || p == Phase::kLower))
    settled_after_s_ = std::max(settled_after_s_, in.t + cfg_.resume_settle_s);
}

SlipDirection PhaseOneSequencer::slip_direction(const StepInput& in) const {
  if (in.t < settled_after_s_) return SlipDirection{};
  return analyze_slip_direction(in.fingertips, in.flags, cfg_.gravity_axis,
                                cfg_.direction_deadband_mm);
}

void PhaseOneSequencer::track_load(const StepInput& in) noexcept {
  for (std::size_t f = 0; f < kFingertips; ++f) {
    if (in.fingertips[f].fresh) load_[f] = shear_load_along(in.fingertips[f], cfg_.gravity_axis);
  }
}

double PhaseOneSequencer::load() const {
  double sum = 0;
  for (double l : load_)
    sum += l;
  return sum / static_cast<double>(kFingertips);
}

namespace {

bool any_fresh(const StepInput& in) {
  for (const FingertipInput& f : in.fingertips) {
    if (f.fresh) return true;
  }
  return false;
}

Event by_load(EventKind kind, double value, const char* text) {
  Event e;
  e.kind = kind;
  e.value = value;
  e.text = text;
  return e;
}

}  // namespace

// The field detector's lift: after lift_confirm_s, a contact that slipped in most fresh frames
// while the arm rose holds a cap that something holds from below (put it back, as the paper's
// release on the lift); else a load gained beyond load_transfer_n on average is the cap's weight
// arriving: a grasp. A light cap whose load stays within the bound is not classified.
void PhaseOneSequencer::lift_by_load(const StepInput& in, SegmentIds& ids,
                                     StepOutput& out) noexcept {
  if (in.t < settled_after_s_ || !any_fresh(in)) return;
  ++lift_frames_;
  if (in.flags.slip) ++lift_slip_frames_;
  lift_gain_sum_n_ += load() - lift_base_n_;
  if (in.t - lift_start_s_ < cfg_.lift_confirm_s || lift_frames_ < 3) return;
  const double gained = lift_gain_sum_n_ / static_cast<double>(lift_frames_);
  if (2 * lift_slip_frames_ > lift_frames_) {
    seq_.event(by_load(EventKind::kReleaseClassified, gained,
                       "slipping while the arm rises: the cap is held from below"),
               out);
    released_on_lift_ = true;
    enter(Phase::kRelease, in, ids, out);
    return;
  }
  if (gained > cfg_.load_transfer_n) {
    seq_.event(by_load(EventKind::kGraspClassified, gained, "the cap's weight carried on the lift"),
               out);
    grasp_classified_ = true;
  }
}

// The field detector's lowering: the load along gravity falls by half the load the lift brought
// (at least load_transfer_n) in three fresh frames in a row: the cap's weight went to a support.
void PhaseOneSequencer::lower_by_load(const StepInput& in, SegmentIds& ids,
                                      StepOutput& out) noexcept {
  if (any_fresh(in)) {
    const double bound = 0.5 * std::max(carried_n_, cfg_.load_transfer_n);
    const double change = load() - lower_base_n_;
    lower_below_ = in.t >= settled_after_s_ && change < -bound ? lower_below_ + 1 : 0;
    if (lower_below_ >= 3) {
      seq_.event(by_load(EventKind::kReleaseClassified, change,
                         "the load along gravity went to a support"),
                 out);
      enter(Phase::kRelease, in, ids, out);
      return;
    }
  }
  if (seq_.segment_done(in, out)) {
    seq_.abort("lowered to lower_limit_m without the load going to a support", out);
  }
}

void PhaseOneSequencer::lift(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  if (!grasp_classified_ && beyond_paper(cfg_.slip_detector)) {
    // The load transfer is judged over the lift proper: while the weight arrives in the loading
    // phase the light grip slips as it catches up, which is no support holding the cap.
    if (!loading_) lift_by_load(in, ids, out);
    if (released_on_lift_) return;
  } else if (!grasp_classified_) {
    // The paper's rule, in the loading phase too: the weight's slip as it arrives is its grasp.
    const SlipDirection d = slip_direction(in);
    if (d.classification == SlipClass::kGrasp) {
      // The weight pulls the cap along gravity: it is held; keep lifting.
      seq_.event(classified(EventKind::kGraspClassified, d), out);
      grasp_classified_ = true;
    } else if (d.classification == SlipClass::kRelease) {
      // Pushed against gravity while lifting: something still holds the cap from below. The
      // paper's rule says release: put it back and end the task.
      released_on_lift_ = true;
      enter(Phase::kRelease, in, ids, out);
      return;
    }
  }
  if (!seq_.segment_done(in, out)) return;
  if (loading_) {
    loading_ = false;
    begin_lift(in.t, ids, out);
  } else {
    enter(Phase::kTransport, in, ids, out);
  }
}

// Positive slips here (deceleration, vibration) are the estimator's: re-compression. The first
// negative one is the cap meeting the bottle or the ground.
void PhaseOneSequencer::lower(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  if (beyond_paper(cfg_.slip_detector)) {
    lower_by_load(in, ids, out);
    return;
  }
  const SlipDirection d = slip_direction(in);
  if (d.classification == SlipClass::kRelease) {
    seq_.event(classified(EventKind::kReleaseClassified, d), out);
    enter(Phase::kRelease, in, ids, out);
  } else if (seq_.segment_done(in, out)) {
    seq_.abort("lowered to lower_limit_m without a negative slip", out);
  }
}

void PhaseOneSequencer::retracted(StepOutput& out) noexcept {
  if (released_on_lift_) {
    seq_.abort("negative slip on lift: the cap was put back", out);
  } else {
    seq_.finish();
  }
}

void PhaseOneSequencer::step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  defer_classification_on_deadman(in);
  track_load(in);
  switch (seq_.phase()) {
    case Phase::kApproach:
      if (seq_.segment_done(in, out)) enter(Phase::kDescend, in, ids, out);
      break;
    case Phase::kDescend:
      if (seq_.segment_done(in, out)) enter(Phase::kGrasp, in, ids, out);
      break;
    case Phase::kGrasp:
      if (seq_.grasp_settled(in, out)) {
        seq_.event(EventKind::kGraspingEnded, out, "grasp pressure set", grasp_force(in.flags));
        enter(Phase::kLift, in, ids, out);
      }
      break;
    case Phase::kLift:
      lift(in, ids, out);
      break;
    case Phase::kTransport:
      if (seq_.segment_done(in, out)) enter(Phase::kLower, in, ids, out);
      break;
    case Phase::kLower:
      lower(in, ids, out);
      break;
    case Phase::kRelease:
      if (seq_.released(in.t, out)) enter(Phase::kRetract, in, ids, out);
      break;
    case Phase::kRetract:
      if (seq_.segment_done(in, out)) retracted(out);
      break;
    default:
      break;
  }
  out.finger_mode = seq_.finger_mode();
}

Command PhaseOneSequencer::resume(SegmentIds& ids, double t) noexcept {
  const Command c = seq_.resume(ids, t);
  // The resumed segment stops and starts the arm under the cap: its slips are its inertia.
  if (c.kind == CommandKind::kMoveTo) settled_after_s_ = t + cfg_.resume_settle_s;
  return c;
}

}  // namespace tactile::control
