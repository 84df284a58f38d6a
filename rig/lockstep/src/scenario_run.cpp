#include "tactile/rig/scenario_run.hpp"

#include <cmath>

#include "tactile/rig/control_link.hpp"

namespace tactile::rig {
namespace {

// The scorer reads the calibrations from the result: they are set before it is built.
LockstepResult& with_calibrations(LockstepResult& result, const SimulatedSensors& sensors) {
  result.calibrations = sensors.calibrations();
  return result;
}

}  // namespace

const char* scenario_case(const WorldParams& w) {
  if (w.cap.held_to_table) return "cap_held";
  if (w.bottle.displaced_x_m != 0 || w.bottle.displaced_y_m != 0) return "bottle_displaced";
  return "normal";
}

void judge_negative_case(Report& r) {
  if (r.scenario_case == "bottle_displaced") {
    r.negative_case_passed = !r.release_classified && !r.opened_in_air;
  } else if (r.scenario_case == "cap_held") {
    r.negative_case_passed = r.grasp_classified != "grasp";
  } else {
    r.negative_case_passed.reset();
  }
}

bool opens_in_air(control::CommandKind command, CapPlace cap) {
  return command == control::CommandKind::kOpen && cap == CapPlace::kFree;
}

control::ArmFeedback arm_feedback(const World& world) {
  control::ArmFeedback f;
  const ArmState& arm = world.arm();
  f.wrist = {arm.position_m, arm.yaw_rad};
  f.active_segment_id = arm.active_segment_id;
  f.segment_done = arm.segment_done;
  f.holding = arm.holding || arm.stopped;
  for (std::size_t i = 0; i < kFingertips; ++i)
    f.fingertip_position_m[i] = world.fingertip(i).offset_w;
  return f;
}

ScenarioRun::ScenarioRun(const Scenario& sc, const CameraParams& camera, LockstepResult& result,
                         bool record_series)
    : sc_(sc),
      result_(result),
      cfg_(scenario_controller_config(sc)),
      world_(sc.world),
      sensors_(sc, camera, world_.element_normals()),
      scorer_(with_calibrations(result, sensors_), cfg_, record_series),
      transport_(transport_direction(sc.world)),
      max_frames_(static_cast<std::uint64_t>(std::ceil(sc.max_time_s * sc.camera.fps))) {
  Report& rep = result_.report;
  rep.seed = sc.seed;
  rep.scenario_case = scenario_case(sc.world);
  if (sc.calibration) {
    const Calibration& c = sensors_.calibrations()[0];
    rep.sensor = LabSensor{sc.calibration_file.string(), c.width, c.height, c.bit_depth};
  }
  rep.hold = hold_need(sc.world, cfg_.f2_n);
  rep.end_reason = "max_time";
  scorer_.reserve(max_frames_ + 1);
  scorer_.score_crush(sc.world.cap.crush_force_n);
}

bool has_disturbance(const DisturbanceParams& d) {
  return d.pull.force_n > 0 || d.mass_step.added_kg > 0 || d.knock.impulse_ns > 0;
}

void ScenarioRun::start_staged_disturbances(control::Phase phase) {
  const char* stage = control::to_string(phase);
  for (std::size_t k = 0; k < sc_.disturbance_start.size(); ++k) {
    const DisturbanceStart& start = sc_.disturbance_start[k];
    if (!start.stage.empty() && start.stage == stage) {
      // The world keeps the first start of each kind: the stage's first frame.
      world_.start_disturbance(static_cast<DisturbanceKind>(k), world_.time() + start.after_s);
    }
  }
}

bool ScenarioRun::step(int steps, double dt_s) {
  for (int s = 0; s < steps; ++s) {
    if (!world_.step(dt_s)) {
      result_.physics_finite = false;
      result_.report.end_reason = "physics";
      return false;
    }
  }
  return true;
}

bool ScenarioRun::advance_to(double t_s, double dt_s) {
  while (world_.time() + 0.5 * dt_s < t_s) {
    if (!step(1, dt_s)) return false;
  }
  return true;
}

const GroundTruth& ScenarioRun::take_truth(std::uint64_t frame, control::Phase phase) {
  return sensors_.truth().take(world_, frame, slip_threshold_mm(cfg_, phase));
}

void ScenarioRun::score_truth(std::uint64_t frame, double t_s, const GroundTruth& truth,
                              const ControllerState& controller) {
  scorer_.add_truth(frame, t_s, truth, controller, frame_pose(world_, transport_));
  scorer_.add_grip(t_s, grip_truth(world_, truth));
  start_staged_disturbances(controller.phase);
}

control::ArmMotion ScenarioRun::arm_motion(double t_s) {
  return arm_motion_.update(arm_feedback(world_).wrist, t_s);
}

bool ScenarioRun::apply(const control::Command& command) {
  if (opens_in_air(command.kind, world_.cap().place)) result_.report.opened_in_air = true;
  return world_.apply(to_world_command(command));
}

void ScenarioRun::task_ended(double t_s) {
  if (ended_at_s_) return;
  ended_at_s_ = t_s;
  // An aborted task keeps the reason its ABORTED event gave (RunScorer::add_event).
  if (result_.report.completed) result_.report.end_reason = "done";
}

bool ScenarioRun::ended_after_frame(std::uint64_t frames, double t_s) {
  if (!result_.physics_finite) return true;
  if (world_.cap().dropped && !dropped_at_s_) dropped_at_s_ = t_s;
  if (ended_at_s_ && t_s - *ended_at_s_ >= sc_.settle_after_done_s) return true;
  if (dropped_at_s_ && t_s - *dropped_at_s_ >= kDroppedEndsAfterS) {
    result_.report.end_reason = "dropped";
    return true;
  }
  return frames >= max_frames_;
}

void ScenarioRun::finish(double sim_time_s, std::uint64_t frames) {
  scorer_.finish(world_.cap().dropped, sim_time_s, frames);
  if (has_disturbance(world_.params().disturbance))
    result_.report.disturbance = world_.params().disturbance;
  judge_negative_case(result_.report);
}

}  // namespace tactile::rig
