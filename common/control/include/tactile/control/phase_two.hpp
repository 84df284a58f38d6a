#pragma once

// Phase II, grasp-twist (paper Fig. 8, docs/control.md): from the reference pose, cycles of
//
//   TWIST_GRASP (SEARCH until TOUCH on both fingertips, settle) -> TWIST_TURN (turn the wrist by
//   the twist angle, counting slip detections) -> TWIST_RELEASE (open) -> TWIST_RETURN (turn
//   back)
//
// until the cap is tight: Ns slip detections within one cycle's turn, or slip detected in the
// turns of two consecutive cycles; with slip_detector field also the twist torque that stops
// building in the turn (TwistTorquePlateau), whichever comes first. Then TWIST_FINISH: hold (stop
// turning), open, move clear, done. max_twist_cycles without tightness ends the same way with
// ABORTED. No slip direction analysis here; dr is scaled by twist_dr_factor.
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/sequencer.hpp"
#include "tactile/control/twist_torque.hpp"

namespace tactile::control {

// With the field and learned detectors a turn's slip detection needs this many slipping elements
// on the fingertip (the paper's rule counts any SLIP).
inline constexpr std::uint32_t kTwistSlipElements = 2;

class PhaseTwoSequencer {
 public:
  explicit PhaseTwoSequencer(const Config& cfg) : cfg_(cfg), seq_(cfg_), torque_(cfg_) {}

  // Enters TWIST_APPROACH toward `reference` (where the cap was released).
  void start(const WristPose& reference, const StepInput& in, SegmentIds& ids,
             StepOutput& out) noexcept;
  void step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  Command resume(SegmentIds& ids, double t) noexcept { return seq_.resume(ids, t); }

  Phase phase() const { return seq_.phase(); }
  // The margin grip's feed-forward: Sequencer::accelerates_within.
  bool accelerates_within(const ArmFeedback& arm, double t, double lead_s) const noexcept {
    return seq_.accelerates_within(arm, t, lead_s);
  }
  bool finished() const { return seq_.phase() == Phase::kDone; }
  std::uint32_t cycle() const { return seq_.cycle(); }
  // The cycle in which tightness was detected (0: not detected).
  std::uint32_t tight_cycle() const { return tight_cycle_; }
  // Slip detections counted in the current cycle's turn.
  std::uint32_t cycle_slips() const { return cycle_slips_; }
  // The twist torque rule of the current turn (slip_detector field).
  const TwistTorquePlateau& twist_torque() const { return torque_; }

 private:
  void enter(Phase p, const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void begin_cycle(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void turn(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void returned(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void let_go(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void retreat(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  // Which of the paper's tightening rules the current turn meets; nullptr while none does.
  const char* tightness() const;
  // The twist torque rule's update; true once the torque stopped building (`turned`: the turn's
  // segment is done).
  bool torque_stopped_building(const StepInput& in, bool turned) noexcept;
  bool tight() const { return tight_cycle_ != 0; }
  double turned_yaw() const;

  Config cfg_;
  Sequencer seq_;
  TwistTorquePlateau torque_;
  WristPose reference_;
  std::uint32_t cycle_slips_ = 0;
  bool previous_cycle_slipped_ = false;
  std::uint32_t tight_cycle_ = 0;
};

}  // namespace tactile::control
