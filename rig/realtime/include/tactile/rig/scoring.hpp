#pragma once

// Scores a run against its ground truth, element-frame by element-frame, and tallies the
// decisions hand_node announced: the scenario report (docs/rig.md, "Lockstep runner and
// report").
// Used by the real-time rig, where measured frames and events arrive over the wire.
#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "tactile/control/config.hpp"
#include "tactile/control/types.hpp"
#include "tactile/reading.hpp"
#include "tactile/rig/control_link.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/truth.hpp"

namespace tactile::rig {

class RunScorer {
 public:
  // Fills `run.report` and (with `record_series`) `run.series`; `run.calibrations` must be set.
  RunScorer(LockstepResult& run, const control::Config& cfg, bool record_series);

  // The truth of one rendered frame (adds a series sample; keeps cap and tightening facts).
  void add_truth(const GroundTruth& truth, std::uint32_t twist_cycle);
  // One measured frame of one fingertip with the truth of the same instant. `frame` counts
  // rendered frames from the start (latency is in frames).
  void add_measurement(std::size_t fingertip, std::uint64_t frame, double t,
                       std::span<const ElementReading> measured, const FingertipTruth& truth,
                       double threshold_mm, const World& world);
  void add_event(control::EventKind kind, control::Phase phase, std::uint32_t cycle,
                 std::string_view text, double value, double t);
  // Closes the metrics.
  void finish(const World& world, double sim_time_s, std::uint64_t frames);

 private:
  FrameSample* sample_for(double t);

  LockstepResult& run_;
  control::Config cfg_;
  bool record_;
  SlipScorer slip_;
  double sq_normal_ = 0;
  double sq_shear_ = 0;
  std::uint64_t n_normal_ = 0;
  std::uint64_t n_shear_ = 0;
};

}  // namespace tactile::rig
