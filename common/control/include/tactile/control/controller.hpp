#pragma once

// The grasp-move-twist controller: the flag analyzer, the finger speed estimator and the two
// sequencers behind one allocation-free update() (docs/control.md).
//
// Each update: flags from the latest readings; if any fingertip is stale, Hold (once, with a
// STALE_HOLD event) and nothing else until no fingertip is stale (RESUMED, and the current step
// continues). Otherwise the active sequencer steps on the task time, the estimator computes the
// finger velocities for the sequencer's mode, and one command goes out: the sequencer's if it
// has one, else the finger velocities if they differ from the last sent.
#include <array>
#include <cstdint>
#include <optional>

#include "tactile/control/config.hpp"
#include "tactile/control/finger_speed_estimator.hpp"
#include "tactile/control/flag_analyzer.hpp"
#include "tactile/control/phase_one.hpp"
#include "tactile/control/phase_two.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

class GraspMoveTwistController {
 public:
  // Validates the configuration (std::invalid_argument naming the field).
  explicit GraspMoveTwistController(const Config& cfg);

  // Allocates nothing, never throws; every number in the output is finite.
  ControllerOutput update(const ControllerInput& in) noexcept;

  // DONE or ABORTED was emitted; every later update sends nothing.
  bool done() const { return phase_ == Phase::kDone || phase_ == Phase::kAborted; }
  Phase phase() const { return phase_; }
  const Config& config() const { return cfg_; }
  // Time the task has run, stale holds excluded (s).
  double task_time() const { return task_s_; }
  const PhaseTwoSequencer& phase_two() const { return two_; }
  const FingerSpeedEstimator& finger_speeds() const { return speed_; }

 private:
  enum class Stage : std::uint8_t { kNotStarted, kPhaseOne, kPhaseTwo, kEnded };

  void step_sequencers(const ControllerInput& in, const Flags& flags, StepOutput& out) noexcept;
  // DONE or ABORTED from the controller itself, with Stop.
  void end(EventKind kind, const char* text, StepOutput& out) noexcept;
  void event(EventList& events, EventKind kind, const char* text,
             std::int8_t fingertip = kNoFingertip, double value = 0,
             std::optional<std::uint32_t> element = std::nullopt) const;
  Phase current_phase() const;
  // What the sequencers say of the next moments, for the margin grip.
  GripContext grip_context(const ArmFeedback& arm) const noexcept;

  Config cfg_;
  FlagAnalyzer flags_;
  SlipDetector detector_;
  ArmMotionEstimator arm_motion_;
  FingerSpeedEstimator speed_;
  PhaseOneSequencer one_;
  PhaseTwoSequencer two_;
  SegmentIds ids_;

  Stage stage_ = Stage::kNotStarted;
  Phase phase_ = Phase::kIdle;
  FingerMode mode_ = FingerMode::kOff;
  std::array<Vec3, kFingertips> sent_velocity_{};
  Phase ended_phase_ = Phase::kDone;
  bool stale_holding_ = false;
  double stale_held_s_ = 0;
  bool has_last_now_ = false;
  double last_now_s_ = 0;
  double task_s_ = 0;
};

}  // namespace tactile::control
