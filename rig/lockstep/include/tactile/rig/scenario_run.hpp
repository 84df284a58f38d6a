#pragma once

// The one core of a rig run (docs/rig.md, "One scenario core"; architecture.md, rules 1 and 9):
// the world, the simulated sensors, the truth and its scorer, what the arm controller reports of
// the world, the commands carried out on it and the rules that end the run. The lockstep runner
// drives it on simulated time, with the measurement and control cores in its own loop; the
// real-time rig drives it by the wall clock, with sensor_node and hand_node over the wire. Both
// then decide the same things the same way: when a run ends and why, whether the fingers opened
// with the cap in the air, the report's case and its judgement. Pure: times are arguments.
#include <cstdint>
#include <optional>

#include "tactile/control/config.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/control/types.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/scoring.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {

// The scenario's case (Report::scenario_case) from its world: "cap_held", "bottle_displaced" or
// "normal".
const char* scenario_case(const WorldParams& world);
// Sets report.negative_case_passed from the case and the classifications (and opened_in_air).
void judge_negative_case(Report& report);

// What an arm controller reports of the world's arm: the control core's ArmFeedback (a stopped
// arm holds). The real-time rig's ArmState and the lockstep runner's feedback both come from it.
control::ArmFeedback arm_feedback(const World& world);

// Whether the world has a disturbance (a pull, a mass step or a knock: docs/rig.md).
bool has_disturbance(const DisturbanceParams& d);

// A drop by command: the fingers told to open with nothing under the cap (neither the table nor
// the bottle), Report::opened_in_air.
bool opens_in_air(control::CommandKind command, CapPlace cap);

// How long after the cap hits the table a run ends ("dropped").
inline constexpr double kDroppedEndsAfterS = 0.5;

class ScenarioRun {
 public:
  // Sets up the world, the sensors (with `camera`, the scenario's or one the runner changed) and
  // the scorer, and fills `result`'s calibrations and the report's seed, case and hold need.
  // `result` must outlive the run. Throws std::invalid_argument for a bad scenario.
  ScenarioRun(const Scenario& scenario, const CameraParams& camera, LockstepResult& result,
              bool record_series);

  const control::Config& config() const { return cfg_; }
  World& world() { return world_; }
  const World& world() const { return world_; }
  SimulatedSensors& sensors() { return sensors_; }
  RunScorer& scorer() { return scorer_; }

  // Steps the world `steps` times by `dt_s`. False when a step gave a non-finite state: the run
  // ends ("physics").
  bool step(int steps, double dt_s);
  // Steps the world by `dt_s` until its clock is within half a step of `t_s`; false as step().
  bool advance_to(double t_s, double dt_s);

  // The truth of frame `frame` (counted as the runner counts its frames), with the slip threshold
  // of `phase`, the phase the controller was in when the frame was taken.
  const GroundTruth& take_truth(std::uint64_t frame, control::Phase phase);
  // Scores `truth`, taken for frame `frame` at `t_s` (counted from the run's start), with the
  // controller's state then, the hand's pose and the grip's truth (grip_truth) now. A disturbance
  // timed from the controller's stage then starts (its time into the stage from now on the
  // world's clock) the first time that stage is seen.
  void score_truth(std::uint64_t frame, double t_s, const GroundTruth& truth,
                   const ControllerState& controller);
  // The arm's motion as its controller sees it from the reported wrist pose at `t_s`.
  control::ArmMotion arm_motion(double t_s);

  // Carries out a command of the controller on the world; true when the world took it. One that
  // opens the fingers in the air (opens_in_air) is remembered (Report::opened_in_air).
  bool apply(const control::Command& command);

  // The controller's task ended (DONE or ABORTED) at `t_s`; the first call counts.
  void task_ended(double t_s);
  // Whether the run ends after the frame that brought its frame count to `frames`, at `t_s`: the
  // scenario's settle time after the task ended, half a second after the cap fell, or
  // max_time_s. Sets the report's end_reason ("done", "dropped"; "max_time" otherwise, and
  // "physics" after a failed step).
  bool ended_after_frame(std::uint64_t frames, double t_s);
  bool task_has_ended() const { return ended_at_s_.has_value(); }

  // Closes the scores and judges the case: call once, at the end.
  void finish(double sim_time_s, std::uint64_t frames);

 private:
  void start_staged_disturbances(control::Phase phase);

  const Scenario& sc_;
  LockstepResult& result_;
  const control::Config cfg_;
  World world_;
  SimulatedSensors sensors_;
  RunScorer scorer_;
  const Vec3 transport_;
  const std::uint64_t max_frames_;
  control::ArmMotionEstimator arm_motion_;
  std::optional<double> ended_at_s_;
  std::optional<double> dropped_at_s_;
};

}  // namespace tactile::rig
