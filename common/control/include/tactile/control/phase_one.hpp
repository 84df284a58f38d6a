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
  explicit PhaseOneSequencer(const Config& cfg) : cfg_(cfg), seq_(cfg_) {}

  // Enters APPROACH.
  void start(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  // The command that continues the current step after a stale hold stopped the arm: the
  // unfinished segment again under a new id, or the interrupted open; kNone otherwise.
  Command resume(SegmentIds& ids, double t) noexcept;

  Phase phase() const { return seq_.phase(); }
  // The lift's loading phase runs (lift_loads_first): the weight arrives.
  bool loading() const { return loading_; }
  // The margin grip's feed-forward: Sequencer::accelerates_within.
  bool accelerates_within(const ArmFeedback& arm, double t, double lead_s) const noexcept {
    return seq_.accelerates_within(arm, t, lead_s);
  }
  // RETRACT completed after a release: Phase I is over.
  bool finished() const { return seq_.phase() == Phase::kDone; }
  // Where the cap was let go (the wrist when the release's open completed): Phase II's
  // reference pose.
  const WristPose& release_pose() const { return release_pose_; }

 private:
  void enter(Phase p, const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void lift(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  // MOVE3 to the carry height at the lift's speed; the lift's classification counts from here.
  void begin_lift(double t, SegmentIds& ids, StepOutput& out) noexcept;
  // The field detector's lift and lowering: classified from the load transfer.
  void track_load(const StepInput& in) noexcept;
  double load() const;
  void lift_by_load(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void lower_by_load(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void lower(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void retracted(StepOutput& out) noexcept;
  void defer_classification_on_deadman(const StepInput& in) noexcept;
  SlipDirection slip_direction(const StepInput& in) const;
  MoveTo travel(const char* name, WristPose target, double speed) const;
  MoveTo carry(const char* name, WristPose target, double speed) const;
  WristPose above_cap(double z) const;
  WristPose above_bottle(double z) const;
  WristPose released_at(const ArmFeedback& arm) const;

  Config cfg_;
  Sequencer seq_;
  double settled_after_s_ = 0;  // no slip direction is classified before this (resume_settle_s)
  bool grasp_classified_ = false;
  bool released_on_lift_ = false;
  bool loading_ = false;  // the lift's loading phase (MOVE3's first, slow part) runs
  WristPose release_pose_;
  // The load transfer (field detector): each fingertip's load along gravity on its latest fresh
  // frame; the load when the lift began; over the lift so far, the fresh frames, those with
  // SLIP and the sum of the load gained; when the lowering began, the load and the load the lift
  // brought (the cap's weight as the fingertips carry it); fresh frames in a row below the
  // release's bound.
  std::array<double, kFingertips> load_{};
  double lift_base_n_ = 0;
  double lift_start_s_ = 0;
  std::uint32_t lift_frames_ = 0;
  std::uint32_t lift_slip_frames_ = 0;
  double lift_gain_sum_n_ = 0;
  double lower_base_n_ = 0;
  double carried_n_ = 0;
  std::uint32_t lower_below_ = 0;
};

}  // namespace tactile::control
