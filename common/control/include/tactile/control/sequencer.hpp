#pragma once

// Pieces shared by the Phase I and Phase II sequencers: what a step sees, what it produces, and
// the bookkeeping of one trajectory segment.
#include <algorithm>
#include <array>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/segment_runner.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

struct StepInput {
  const std::array<FingertipInput, kFingertips>& fingertips;
  const Flags& flags;
  const ArmFeedback& arm;
  double t;  // task time (s): the controller's clock, frozen during stale holds
};

struct StepOutput {
  Command command;  // at most one per update
  EventList& events;
  FingerMode finger_mode = FingerMode::kOff;
};

// The segment a step waits for.
struct ActiveSegment {
  bool active = false;
  MoveTo move;
  double started_s = 0;

  bool done(const ArmFeedback& arm) const {
    return active && arm.active_segment_id == move.segment_id && arm.segment_done;
  }
};

// The open that carries on after a stale hold stopped one that had run for `elapsed_s` (task
// time, which stale holds do not advance): only the distance it had left, so that holds never
// add up to a wider open. kNone when it had finished its stroke.
inline Command resume_open(const Config& cfg, double elapsed_s) noexcept {
  const double left = cfg.open_distance_m - cfg.open_speed_mps * std::max(elapsed_s, 0.0);
  if (!(left > 0)) return Command::none();
  return Command::open_fingers({cfg.open_speed_mps, left});
}

}  // namespace tactile::control
