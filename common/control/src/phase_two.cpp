#include "tactile/control/phase_two.hpp"

#include <algorithm>
#include <cmath>

#include "tactile/control/slip_direction.hpp"

namespace tactile::control {

// Clockwise seen from above when tighten_clockwise: the yaw decreases.
double PhaseTwoSequencer::turned_yaw() const {
  const double sign = cfg_.tighten_clockwise ? -1.0 : 1.0;
  return reference_.yaw_rad + sign * cfg_.twist_angle_rad;
}

void PhaseTwoSequencer::enter(Phase p, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  seq_.enter(p, out);
  const double t = in.t;
  switch (p) {
    case Phase::kTwistApproach:
      seq_.move(MoveTo{0, "TWIST0", reference_, cfg_.move_speed_mps, cfg_.max_yaw_rate_rps, false},
                t, ids, out);
      break;
    case Phase::kTwistGrasp:
      seq_.search(t);
      break;
    case Phase::kTwistTurn: {
      torque_.start(t);
      // The fingers keep their velocities: a slip while turning is answered by re-compression.
      const WristPose turned{reference_.position_m, turned_yaw()};
      seq_.move(MoveTo{0, "TURN", turned, cfg_.move_speed_mps, cfg_.twist_yaw_rate_rps, true}, t,
                ids, out);
      break;
    }
    case Phase::kTwistRelease:
      seq_.open(t, out);
      break;
    case Phase::kTwistReturn:
      seq_.move(
          MoveTo{0, "RETURN", reference_, cfg_.move_speed_mps, cfg_.twist_yaw_rate_rps, false}, t,
          ids, out);
      break;
    case Phase::kTwistFinish:
      if (tight()) {
        // Stop turning at once.
        seq_.hold_then_open(out);
      } else {
        // The cycle cap: the fingers are open and back at the reference already.
        retreat(in, ids, out);
      }
      break;
    default:
      break;
  }
}

// Straight up with the yaw the wrist has now, kept between the reference and the full turn.
void PhaseTwoSequencer::retreat(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  const double a = reference_.yaw_rad;
  const double b = turned_yaw();
  double yaw = in.arm.wrist.yaw_rad;
  if (!std::isfinite(yaw)) yaw = a;
  yaw = std::clamp(yaw, std::min(a, b), std::max(a, b));
  WristPose up{reference_.position_m, yaw};
  up.position_m.z += cfg_.retract_height_m;
  seq_.move(MoveTo{0, "RETREAT", up, cfg_.move_speed_mps, cfg_.max_yaw_rate_rps, false}, in.t, ids,
            out);
}

void PhaseTwoSequencer::begin_cycle(const StepInput& in, SegmentIds& ids,
                                    StepOutput& out) noexcept {
  const std::uint32_t cycle = seq_.next_cycle();
  cycle_slips_ = 0;
  seq_.event(EventKind::kTwistCycle, out, "twist cycle", static_cast<double>(cycle));
  enter(Phase::kTwistGrasp, in, ids, out);
}

void PhaseTwoSequencer::start(const WristPose& reference, const StepInput& in, SegmentIds& ids,
                              StepOutput& out) noexcept {
  reference_ = reference;
  cycle_slips_ = 0;
  previous_cycle_slipped_ = false;
  tight_cycle_ = 0;
  seq_.restart();
  enter(Phase::kTwistApproach, in, ids, out);
  out.finger_mode = seq_.finger_mode();
}

const char* PhaseTwoSequencer::tightness() const {
  if (cycle_slips_ >= cfg_.ns) return "Ns slip detections in one cycle";
  if (previous_cycle_slipped_ && cycle_slips_ >= cfg_.cycle_slip_min) {
    return "slip detected in two consecutive cycles";
  }
  return nullptr;
}

void PhaseTwoSequencer::turn(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  // A detection is one fresh frame of one fingertip with SLIP raised (docs/control.md); with the
  // field and learned detectors, on at least kTwistSlipElements elements: they decide each
  // element from more signals than its motion, and a single element's false slip in each of two
  // turns would declare a free-turning cap tight by the two-cycle rule.
  // The margin grip holds the cap lightly: the turn's own start shears the contact past its rim's
  // stick, a slip of the arm's acceleration, not of the cap's resistance (the grip answers it as
  // it does the carry's); the paper's grip, at F1, counts every slip as the paper does.
  const bool starting =
      cfg_.grip == GripKind::kMargin && seq_.segment_started_within(in.t, cfg_.grip_ff_lead_s);
  for (const FingertipFlags& f : in.flags.fingertip) {
    const bool counts =
        !starting && f.slip &&
        (!beyond_paper(cfg_.slip_detector) || f.slipping_elements >= kTwistSlipElements);
    if (counts) ++cycle_slips_;
  }
  const char* why = tightness();
  bool turned = false;
  if (why == nullptr) {
    turned = seq_.segment_done(in, out);
    if (seq_.phase() != Phase::kTwistTurn) return;  // the segment timed out: ABORTED
    if (beyond_paper(cfg_.slip_detector) && torque_stopped_building(in, turned)) {
      why = "twist torque stopped building";
    }
  }
  if (why != nullptr) {
    tight_cycle_ = seq_.cycle();
    seq_.event(EventKind::kCapTight, out, why, static_cast<double>(cycle_slips_));
    enter(Phase::kTwistFinish, in, ids, out);
  } else if (turned) {
    enter(Phase::kTwistRelease, in, ids, out);
  }
}

bool PhaseTwoSequencer::torque_stopped_building(const StepInput& in, bool turned) noexcept {
  bool fresh = false;
  for (const FingertipInput& f : in.fingertips)
    fresh = fresh || f.fresh;
  // The cap resists the turn: the fingertips' torque on it points along the turn.
  const double sign = cfg_.tighten_clockwise ? -1.0 : 1.0;
  const double torque = sign * twist_torque_nm(in.fingertips, in.arm);
  return torque_.update(torque, fresh, turned, in.t);
}

void PhaseTwoSequencer::returned(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  previous_cycle_slipped_ = cycle_slips_ >= cfg_.cycle_slip_min;
  if (seq_.cycle() >= cfg_.max_twist_cycles) {
    enter(Phase::kTwistFinish, in, ids, out);
  } else {
    begin_cycle(in, ids, out);
  }
}

// Hold, open, then RETREAT; or, after the cycle cap, RETREAT alone.
void PhaseTwoSequencer::let_go(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  if (seq_.released(in.t, out)) {
    retreat(in, ids, out);
  } else if (seq_.segment_done(in, out)) {
    if (tight()) {
      seq_.finish();
    } else {
      seq_.abort("no tightness detected within max_twist_cycles", out);
    }
  }
}

void PhaseTwoSequencer::step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept {
  switch (seq_.phase()) {
    case Phase::kTwistApproach:
      if (seq_.segment_done(in, out)) begin_cycle(in, ids, out);
      break;
    case Phase::kTwistGrasp:
      if (seq_.grasp_settled(in, out)) enter(Phase::kTwistTurn, in, ids, out);
      break;
    case Phase::kTwistTurn:
      turn(in, ids, out);
      break;
    case Phase::kTwistRelease:
      if (seq_.released(in.t, out)) enter(Phase::kTwistReturn, in, ids, out);
      break;
    case Phase::kTwistReturn:
      if (seq_.segment_done(in, out)) returned(in, ids, out);
      break;
    case Phase::kTwistFinish:
      let_go(in, ids, out);
      break;
    default:
      break;
  }
  out.finger_mode = seq_.finger_mode();
}

}  // namespace tactile::control
