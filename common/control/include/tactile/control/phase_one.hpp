#pragma once

// Phase I, grasp-move-release (paper Fig. 7, docs/control.md):
//
//   APPROACH (MOVE1) -> DESCEND (MOVE2) -> GRASP (SEARCH until TOUCH on both fingertips, settle,
//   "grasping ended") -> LIFT (MOVE3, the first classified slip: positive = grasp, negative =
//   put it back and abort) -> TRANSPORT (MOVE4) -> LOWER (MOVE5 toward an unknown height, the
//   first negative slip = release) -> RELEASE (hold, open gently) -> RETRACT (MOVE6).
//
// Slips during LIFT, TRANSPORT and LOWER are answered by the finger speed estimator (MOVE mode)
// with re-compression; this class only decides the steps.
#include <array>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/sequencer.hpp"
#include "tactile/control/slip_direction.hpp"

namespace tactile::control {

class PhaseOneSequencer {
 public:
  explicit PhaseOneSequencer(const Config& cfg) : cfg_(cfg) {}

  // Enters APPROACH.
  void start(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  // The command that continues the current step after a stale hold stopped the arm: the
  // unfinished segment again under a new id, or the interrupted open; kNone otherwise.
  Command resume(SegmentIds& ids, double t) noexcept;

  Phase phase() const { return phase_; }
  // RETRACT completed after a release: Phase I is over.
  bool finished() const { return finished_; }
  // Where the cap was let go (the wrist when the release's open completed): Phase II's
  // reference pose.
  const WristPose& release_pose() const { return release_pose_; }

 private:
  enum class Sub : std::uint8_t { kNone, kSearch, kSettle, kHolding, kOpening };

  void enter(Phase p, const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void issue(const char* name, WristPose target, double speed, double yaw_rate, bool keep,
             const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void abort(const char* why, StepOutput& out) noexcept;
  void event(EventKind kind, StepOutput& out, const char* text = "", double value = 0) const;
  bool segment_timed_out(double t) const;
  WristPose place(double x, double y, double z) const;

  Config cfg_;
  Phase phase_ = Phase::kIdle;
  Sub sub_ = Sub::kNone;
  double sub_started_s_ = 0;
  double settled_after_s_ = 0;  // no slip direction is classified before this (resume_settle_s)
  ActiveSegment segment_;
  std::array<bool, kFingertips> touched_{};
  bool grasp_classified_ = false;
  bool released_on_lift_ = false;
  bool finished_ = false;
  WristPose release_pose_;
};

}  // namespace tactile::control
