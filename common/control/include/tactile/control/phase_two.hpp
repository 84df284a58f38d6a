#pragma once

// Phase II, grasp-twist (paper Fig. 8, docs/control.md): from the reference pose, cycles of
//
//   TWIST_GRASP (SEARCH until TOUCH on both fingertips, settle) -> TWIST_TURN (turn the wrist by
//   the twist angle, counting slip detections) -> TWIST_RELEASE (open) -> TWIST_RETURN (turn
//   back)
//
// until the cap is tight: Ns slip detections within one cycle's turn, or slip detected in the
// turns of two consecutive cycles. Then TWIST_FINISH: hold (stop turning), open, move clear,
// done. max_twist_cycles without tightness ends the same way with ABORTED. No slip direction
// analysis here; dr is scaled by twist_dr_factor.
#include <array>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/sequencer.hpp"

namespace tactile::control {

class PhaseTwoSequencer {
 public:
  explicit PhaseTwoSequencer(const Config& cfg) : cfg_(cfg) {}

  // Enters TWIST_APPROACH toward `reference` (where the cap was released).
  void start(const WristPose& reference, const StepInput& in, SegmentIds& ids,
             StepOutput& out) noexcept;
  void step(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  Command resume(SegmentIds& ids, double t) noexcept;

  Phase phase() const { return phase_; }
  bool finished() const { return finished_; }
  std::uint32_t cycle() const { return cycle_; }
  // The cycle in which tightness was detected (0: not detected).
  std::uint32_t tight_cycle() const { return tight_cycle_; }
  // Slip detections counted in the current cycle's turn.
  std::uint32_t cycle_slips() const { return cycle_slips_; }

 private:
  enum class Sub : std::uint8_t { kNone, kSearch, kSettle, kHolding, kOpening, kRetreat };

  void enter(Phase p, const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void begin_cycle(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void finish(const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void issue(const char* name, WristPose target, double speed, double yaw_rate, bool keep,
             const StepInput& in, SegmentIds& ids, StepOutput& out) noexcept;
  void abort(const char* why, StepOutput& out) noexcept;
  void event(EventKind kind, StepOutput& out, const char* text = "", double value = 0) const;
  bool segment_timed_out(double t) const;
  void start_open(double t, StepOutput& out) noexcept;
  bool open_complete(double t) const;

  Config cfg_;
  Phase phase_ = Phase::kIdle;
  Sub sub_ = Sub::kNone;
  double sub_started_s_ = 0;
  ActiveSegment segment_;
  WristPose reference_;
  std::array<bool, kFingertips> touched_{};
  std::uint32_t cycle_ = 0;
  std::uint32_t cycle_slips_ = 0;
  bool previous_cycle_slipped_ = false;
  std::uint32_t tight_cycle_ = 0;
  bool gave_up_ = false;  // max_twist_cycles reached without tightness
  bool finished_ = false;
};

}  // namespace tactile::control
