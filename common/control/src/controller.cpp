#include "tactile/control/controller.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace tactile::control {

namespace {

// A clock jump longer than this counts as this much: timers expire, but a step cannot be skipped
// by a bad timestamp.
constexpr double kMaxStepS = 1.0;

bool stops_fingers(const Command& c) {
  switch (c.kind) {
    case CommandKind::kHold:
    case CommandKind::kOpen:
    case CommandKind::kStop:
      return true;
    case CommandKind::kMoveTo:
      return !c.move_to.keep_finger_velocities;
    default:
      return false;
  }
}

bool same(const std::array<Vec3, kFingertips>& a, const std::array<Vec3, kFingertips>& b) {
  for (std::size_t f = 0; f < kFingertips; ++f) {
    if (a[f].x != b[f].x || a[f].y != b[f].y || a[f].z != b[f].z) return false;
  }
  return true;
}

std::optional<std::uint32_t> element_id(const FingertipInput& in, std::int32_t index) {
  if (index < 0 || static_cast<std::size_t>(index) >= in.elements.size()) return std::nullopt;
  return in.elements[static_cast<std::size_t>(index)].id;
}

bool finite(const WristPose& p) {
  return is_finite(p.position_m) && std::isfinite(p.yaw_rad);
}

const Config& validated(const Config& cfg) {
  cfg.validate();
  return cfg;
}
}  // namespace

GraspMoveTwistController::GraspMoveTwistController(const Config& cfg)
    : cfg_(validated(cfg)), flags_(cfg_), detector_(cfg_), speed_(cfg_), one_(cfg_), two_(cfg_) {}

Phase GraspMoveTwistController::current_phase() const {
  switch (stage_) {
    case Stage::kNotStarted:
      return Phase::kIdle;
    case Stage::kPhaseOne:
      return one_.phase();
    case Stage::kPhaseTwo:
      return two_.phase();
    case Stage::kEnded:
      return ended_phase_;
  }
  return Phase::kIdle;
}

void GraspMoveTwistController::event(EventList& events, EventKind kind, const char* text,
                                     std::int8_t fingertip, double value,
                                     std::optional<std::uint32_t> element) const {
  Event e;
  e.has_element = element.has_value();
  e.element_id = element.value_or(0);
  e.kind = kind;
  e.phase = phase_;
  e.cycle = stage_ == Stage::kPhaseTwo ? two_.cycle() : 0;
  e.fingertip = fingertip;
  e.value = value;
  e.text = text;
  events.push(e);
}

GripContext GraspMoveTwistController::grip_context(const ArmFeedback& arm) const noexcept {
  GripContext c;
  const double lead_s = cfg_.grip_ff_lead_s;
  if (stage_ == Stage::kPhaseOne) {
    c.carrying = phase_ == Phase::kLift || phase_ == Phase::kTransport;
    c.lifting = phase_ == Phase::kGrasp || phase_ == Phase::kLift;
    c.loading = phase_ == Phase::kLift && one_.loading();
    c.accelerates_soon = one_.accelerates_within(arm, task_s_, lead_s);
  } else if (stage_ == Stage::kPhaseTwo) {
    c.twist = true;
    c.accelerates_soon = two_.accelerates_within(arm, task_s_, lead_s);
  }
  return c;
}

void GraspMoveTwistController::end(EventKind kind, const char* text, StepOutput& out) noexcept {
  event(out.events, kind, text);
  stage_ = Stage::kEnded;
  ended_phase_ = kind == EventKind::kDone ? Phase::kDone : Phase::kAborted;
  out.command = Command::stop();
  out.finger_mode = FingerMode::kOff;
}

void GraspMoveTwistController::step_sequencers(const ControllerInput& in, const Flags& flags,
                                               StepOutput& out) noexcept {
  const StepInput step{in.fingertips, flags, in.arm, task_s_, speed_.grip_ready()};
  switch (stage_) {
    case Stage::kNotStarted:
      if (cfg_.task == Task::kTwistOnly) {
        if (!finite(in.arm.wrist)) {
          end(EventKind::kAborted, "twist only: no valid wrist pose to twist at", out);
          return;
        }
        stage_ = Stage::kPhaseTwo;
        two_.start(in.arm.wrist, step, ids_, out);
      } else {
        stage_ = Stage::kPhaseOne;
        one_.start(step, ids_, out);
      }
      return;
    case Stage::kPhaseOne:
      one_.step(step, ids_, out);
      if (one_.finished()) {
        if (cfg_.task == Task::kGraspMoveTwist) {
          stage_ = Stage::kPhaseTwo;
          two_.start(one_.release_pose(), step, ids_, out);
        } else {
          end(EventKind::kDone, "cap placed", out);
        }
      }
      return;
    case Stage::kPhaseTwo:
      two_.step(step, ids_, out);
      if (two_.finished()) end(EventKind::kDone, "cap tight", out);
      return;
    case Stage::kEnded:
      return;
  }
}

ControllerOutput GraspMoveTwistController::update(const ControllerInput& in) noexcept {
  ControllerOutput out;
  // SLIP from the configured detector, on the threshold of the step the frame was taken in.
  const ArmMotion arm = arm_motion_.update(in.arm.wrist, in.now_s);
  const double threshold = flags_.dr(is_twist_phase(phase_));
  std::array<const FingertipSlip*, kFingertips> slips{};
  for (std::size_t f = 0; f < kFingertips; ++f)
    slips[f] = &detector_.update(f, in.fingertips[f], threshold, arm);
  out.flags = flags_.analyze(in.fingertips, mode_, slips);
  out.slip_detector = detector_.kind();
  out.phase = phase_;
  out.twist_cycle = two_.cycle();
  if (done()) return out;

  double dt = 0;
  if (has_last_now_ && std::isfinite(in.now_s)) {
    dt = in.now_s - last_now_s_;
    dt = std::isfinite(dt) && dt > 0 ? std::min(dt, kMaxStepS) : 0.0;
  }
  if (std::isfinite(in.now_s)) {
    last_now_s_ = in.now_s;
    has_last_now_ = true;
  }

  std::int8_t stale = kNoFingertip;
  for (std::size_t f = 0; f < kFingertips; ++f) {
    if (in.fingertips[f].stale && stale == kNoFingertip) stale = static_cast<std::int8_t>(f);
  }
  if (stale != kNoFingertip) {
    // Nothing may squeeze harder or move on data that no longer describes the grasp.
    StepOutput so{Command::none(), out.events, FingerMode::kOff};
    if (!stale_holding_) {
      stale_holding_ = true;
      stale_held_s_ = 0;
      event(out.events, EventKind::kStaleHold, "tactile data stale", stale);
      so.command = Command::hold();
      speed_.stop_for_stale();
      sent_velocity_ = {};
    } else {
      stale_held_s_ += dt;
      if (cfg_.stale_abort_s > 0 && stale_held_s_ >= cfg_.stale_abort_s) {
        end(EventKind::kAborted, "tactile data stale for stale_abort_s", so);
      }
    }
    out.command = so.command;
    phase_ = current_phase();
    out.phase = phase_;
    out.flags.slip = false;
    for (FingertipFlags& f : out.flags.fingertip) {
      f.slip = false;
      f.slipping_elements = 0;  // what the viewers draw agrees with the SLIP flag held off
    }
    out.flags.search = out.flags.move = false;
    return out;
  }

  task_s_ += dt;
  Command resume = Command::none();
  if (stale_holding_) {
    stale_holding_ = false;
    event(out.events, EventKind::kResumed, "tactile data fresh again");
    if (stage_ == Stage::kPhaseOne) resume = one_.resume(ids_, task_s_);
    if (stage_ == Stage::kPhaseTwo) resume = two_.resume(ids_, task_s_);
  }

  StepOutput so{Command::none(), out.events, mode_};
  step_sequencers(in, out.flags, so);
  Command command = so.command.kind != CommandKind::kNone ? so.command : resume;
  phase_ = current_phase();
  mode_ = done() ? FingerMode::kOff : so.finger_mode;
  if (stops_fingers(command)) {
    speed_.reset();
    sent_velocity_ = {};
  }

  const FingerSpeedOutput v =
      speed_.update(mode_, out.flags, in.fingertips, task_s_, grip_context(in.arm));
  for (std::size_t f = 0; f < kFingertips; ++f) {
    const FingertipFlags& ff = out.flags.fingertip[f];
    const auto tip = static_cast<std::int8_t>(f);
    // Both name the element with the largest F_z: the one over F2, or the one whose inward
    // normal gave the re-compression's direction.
    if (v.over_started[f]) {
      event(out.events, EventKind::kOver, "F_z passed F2: backing off", tip, ff.max_fz_n,
            element_id(in.fingertips[f], ff.max_fz_index));
    }
    if (v.recompress_started[f]) {
      event(out.events, EventKind::kRecompress, "slip: re-compressing", tip, ff.max_slip_mm,
            element_id(in.fingertips[f], ff.max_fz_index));
    }
  }

  if (command.kind == CommandKind::kNone && !same(v.velocity_mps, sent_velocity_)) {
    command = Command::velocities({v.velocity_mps});
    sent_velocity_ = v.velocity_mps;
  }
  out.command = command;
  out.flags.search = mode_ == FingerMode::kSearch;
  out.flags.move = mode_ == FingerMode::kMove;
  out.phase = phase_;
  out.twist_cycle = two_.cycle();
  return out;
}

}  // namespace tactile::control
