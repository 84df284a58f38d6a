#pragma once

// The skeleton both sequencers are built on (Fig. 7 and Fig. 8 share it): the current step and
// its events, the one trajectory segment, the grasp and the gentle release a step runs, ABORTED,
// the finger mode that follows from them, and the resume after a stale hold. A phase sequencer
// keeps only its own transitions: which step comes next and what each step starts.
#include <array>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/gentle_release.hpp"
#include "tactile/control/grasp_search.hpp"
#include "tactile/control/segment_runner.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

struct StepInput {
  const std::array<FingertipInput, kFingertips>& fingertips;
  const Flags& flags;
  const ArmFeedback& arm;
  double t;  // task time (s): the controller's clock, frozen during stale holds
  // The grip has reached what the grip law asks (FingerSpeedEstimator::grip_ready).
  bool grip_ready = true;
};

struct StepOutput {
  Command command;  // at most one per update
  EventList& events;
  FingerMode finger_mode = FingerMode::kOff;
};

class Sequencer {
 public:
  explicit Sequencer(const Config& cfg) noexcept
      : segment_(cfg.segment_timeout_s),
        grasp_(cfg.search_timeout_s, cfg.grasp_settle_s, cfg.grip_reach_timeout_s),
        release_(cfg) {}

  // A new run: idle, nothing running, cycle 0.
  void restart() noexcept;
  // A new step (its PHASE event): whatever the previous one ran is over.
  void enter(Phase p, StepOutput& out) noexcept;
  // The phase is over (kDone); DONE is the controller's to say.
  void finish() noexcept;
  // ABORTED (`why` a literal), Stop, the fingers off.
  void abort(const char* why, StepOutput& out) noexcept;
  // Phase II's twist cycles; every event carries the current one (0 before the first).
  std::uint32_t next_cycle() noexcept { return ++cycle_; }

  // `e` in the current step and cycle.
  void event(Event e, StepOutput& out) const;
  void event(EventKind kind, StepOutput& out, const char* text, double value = 0) const;

  // Sends `move` (a new id), with the segment timeout from now.
  void move(const MoveTo& move, double t, SegmentIds& ids, StepOutput& out) noexcept;
  // The segment is done. Not done within segment_timeout_s: ABORTED.
  bool segment_done(const StepInput& in, StepOutput& out) noexcept;

  // SEARCH from t.
  void search(double t) noexcept { grasp_.start(t); }
  // TOUCH when both fingertips have touched; true when the grasp has settled. Search timed out:
  // ABORTED.
  bool grasp_settled(const StepInput& in, StepOutput& out) noexcept;

  // Stop the arm now, open on the next update.
  void hold_then_open(StepOutput& out) noexcept { out.command = release_.hold(); }
  void open(double t, StepOutput& out) noexcept { out.command = release_.open(t); }
  // Sends the open that follows hold_then_open; true once, when the open has run its course.
  bool released(double t, StepOutput& out) noexcept { return release_.update(t, out.command); }

  // SEARCH while the grasp searches; MOVE while it settles and while a segment carries the
  // object; otherwise off.
  FingerMode finger_mode() const;
  // The command that continues the step after a stale hold stopped the arm: the interrupted
  // open for the distance it had left, or the unfinished segment under a new id; kNone otherwise.
  Command resume(SegmentIds& ids, double t) noexcept;

  // The arm's own planned acceleration is at most lead_s away (the margin grip's feed-forward):
  // the grasp settles (a segment that carries the object follows), or a carrying segment started
  // less than lead_s ago or has less than lead_s left at its speeds.
  bool accelerates_within(const ArmFeedback& arm, double t, double lead_s) const noexcept;
  // The running segment started less than s ago.
  bool segment_started_within(double t, double s) const noexcept {
    return t - segment_.started_s() < s;
  }

  Phase phase() const { return phase_; }
  std::uint32_t cycle() const { return cycle_; }

 private:
  void clear() noexcept;

  Phase phase_ = Phase::kIdle;
  std::uint32_t cycle_ = 0;
  SegmentRunner segment_;
  GraspSearch grasp_;
  GentleRelease release_;
};

}  // namespace tactile::control
