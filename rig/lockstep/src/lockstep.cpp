#include "tactile/rig/lockstep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "tactile/control/config.hpp"
#include "tactile/control/controller.hpp"
#include "tactile/extractor.hpp"
#include "tactile/rig/control_link.hpp"
#include "tactile/rig/scoring.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/rig/world.hpp"
#include "tactile/util/percentile.hpp"

namespace tactile::rig {
namespace {

double ratio(std::uint64_t part, std::uint64_t rest) {
  return part + rest > 0 ? static_cast<double>(part) / static_cast<double>(part + rest) : 1.0;
}

}  // namespace

void SlipScorer::add(std::size_t i, std::size_t k, std::uint64_t frame, bool predicted, bool ideal,
                     const ElementTruth& et, double thr) {
  measured_.add(predicted, et.sliding);
  ideal_.add(ideal, et.sliding);
  Element& es = elements_[i][k];
  const bool changed = et.visible != es.was_visible;
  const double motion = std::max(et.slip_mm, et.surface_mm);
  const bool edge = changed || es.visibility_changed ||
                    (et.load_ratio >= 0.07 && et.load_ratio <= 0.13) ||
                    (motion >= 0.67 * thr && motion <= 1.5 * thr);
  if (edge) {
    ++m_.edge_frames;
  } else {
    clear_.add(predicted, et.sliding);
    ideal_clear_.add(ideal, et.sliding);
  }
  es.was_visible = et.visible;
  es.visibility_changed = changed;
  if (et.sliding && !es.was_sliding) {
    ++m_.onsets;
    if (es.pending) {  // a new episode before the last was covered
      ++m_.missed_onsets;
      latencies_.push_back(kMissedLatencyFrames);
    }
    es.pending = true;
    es.onset = frame;
  }
  if (et.sliding) es.last_true = frame;
  if (es.pending && predicted) {
    latencies_.push_back(static_cast<double>(frame - es.onset));
    es.pending = false;
  } else if (es.pending && !et.sliding && frame > es.last_true + 2) {
    ++m_.missed_onsets;
    latencies_.push_back(kMissedLatencyFrames);
    es.pending = false;
  }
  es.was_sliding = et.sliding;
}

void SlipScorer::finish(SlipMetrics& out) {
  for (auto& tip : elements_) {
    for (Element& es : tip) {
      if (es.pending) {
        ++m_.missed_onsets;
        latencies_.push_back(kMissedLatencyFrames);
        es.pending = false;
      }
    }
  }
  m_.true_positives = measured_.tp;
  m_.false_positives = measured_.fp;
  m_.false_negatives = measured_.fn;
  m_.precision = ratio(measured_.tp, measured_.fp);
  m_.recall = ratio(measured_.tp, measured_.fn);
  m_.ideal_precision = ratio(ideal_.tp, ideal_.fp);
  m_.ideal_recall = ratio(ideal_.tp, ideal_.fn);
  m_.precision_clear = ratio(clear_.tp, clear_.fp);
  m_.recall_clear = ratio(clear_.tp, clear_.fn);
  m_.ideal_precision_clear = ratio(ideal_clear_.tp, ideal_clear_.fp);
  m_.ideal_recall_clear = ratio(ideal_clear_.tp, ideal_clear_.fn);
  m_.latency_frames_p50 = nearest_rank_percentile(latencies_, 0.50);
  m_.latency_frames_p99 = nearest_rank_percentile(latencies_, 0.99);
  const std::string detector = out.detector;
  out = m_;
  out.detector = detector;
}

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

LockstepResult run_lockstep(const Scenario& sc, const LockstepOptions& opt) {
  LockstepResult result;
  Report& rep = result.report;
  rep.seed = sc.seed;
  rep.scenario_case = scenario_case(sc.world);

  const control::Config cfg = scenario_controller_config(sc);
  rep.hold = hold_need(sc.world, cfg.f2_n);
  World world(sc.world);
  const int steps =
      opt.dt_s > 0 ? std::max(1, static_cast<int>(std::lround(1.0 / (sc.camera.fps * opt.dt_s))))
                   : sc.steps_per_frame();
  const double dt = 1.0 / (sc.camera.fps * steps);
  rep.physics_step_s = dt;

  const auto normals = world.element_normals();
  // Only the measurement sees these images, and it reads only the disks: no live background.
  CameraParams camera = sc.camera;
  camera.live_background = false;
  SimulatedSensors sensors(sc, camera, normals);
  result.calibrations = sensors.calibrations();
  std::vector<Extractor> extractors;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    ExtractorOptions eo;
    eo.reference_frames = sc.optics.reference_frames;
    extractors.emplace_back(result.calibrations[i], eo);
  }

  // The no-load reference, captured before the task starts (nothing touches the sensors).
  for (std::size_t i = 0; i < kFingertips; ++i) {
    extractors[i].begin_reference();
    ReferenceResult r{};
    for (int k = 0; k < sc.optics.reference_frames; ++k)
      r = extractors[i].add_reference_frame(sensors.render(i, FingertipTruth{}).view());
    if (r.status != ReferenceStatus::kComplete) {
      throw std::runtime_error(std::string("lockstep: no-load reference refused: ") +
                               to_string(r.status));
    }
  }

  control::GraspMoveTwistController controller(cfg);
  control::ArmMotionEstimator arm_motion;
  control::Phase phase = control::Phase::kIdle;
  bool done_seen = false;
  double done_at = 0;
  double dropped_at = -1;
  RunScorer scorer(result, cfg, opt.record_series);
  if (opt.slip_features != nullptr) scorer.log_features(opt.slip_features);
  const Vec3 transport = transport_direction(sc.world);

  std::uint64_t frame = 0;
  const auto max_frames = static_cast<std::uint64_t>(std::ceil(sc.max_time_s * sc.camera.fps));
  rep.end_reason = "max_time";
  while (frame < max_frames) {
    bool finite = true;
    for (int s = 0; s < steps && finite; ++s)
      finite = world.step(dt);
    if (!finite) {
      result.physics_finite = false;
      rep.end_reason = "physics";
      break;
    }
    ++frame;
    const double t = static_cast<double>(frame) / sc.camera.fps;
    const GroundTruth& gt = sensors.truth().take(world, frame, slip_threshold_mm(cfg, phase));

    // Render and measure both fingertips.
    std::array<control::FingertipInput, control::kFingertips> tips{};
    for (std::size_t i = 0; i < kFingertips; ++i) {
      extractors[i].measure(sensors.render(i, gt.fingertips[i]).view(),
                            {frame, static_cast<std::int64_t>(std::llround(t * 1e9))});
      tips[i].elements = extractors[i].readings();
      tips[i].normals = normals;
      tips[i].sequence = frame;
      tips[i].camera_timestamp_ns = std::llround(t * 1e9);
      tips[i].fresh = true;
      tips[i].stale = false;
    }
    control::ControllerInput in{};
    in.fingertips = tips;
    in.arm.wrist.position_m = world.arm().position_m;
    in.arm.wrist.yaw_rad = world.arm().yaw_rad;
    in.arm.active_segment_id = world.arm().active_segment_id;
    in.arm.segment_done = world.arm().segment_done;
    in.arm.holding = world.arm().holding;
    for (std::size_t i = 0; i < kFingertips; ++i)
      in.arm.fingertip_position_m[i] = world.fingertip(i).offset_w;
    in.now_s = t;
    const control::ControllerOutput out = controller.update(in);
    // The arm's motion as the controller saw it, for the scorer's detectors.
    const control::ArmMotion arm = arm_motion.update(in.arm.wrist, in.now_s);

    scorer.add_truth(frame, t, gt, {out.phase, out.twist_cycle}, frame_pose(world, transport));
    for (std::size_t i = 0; i < kFingertips; ++i)
      scorer.add_measurement(i, frame, extractors[i].readings(), gt.fingertips[i], phase, arm);
    for (const control::Event& e : out.events)
      scorer.add_event(e, t);

    // A drop by command: the fingers told to open with nothing under the cap.
    if (out.command.kind == control::CommandKind::kOpen && world.cap().place == CapPlace::kFree)
      rep.opened_in_air = true;
    world.apply(to_world_command(out.command));
    phase = out.phase;
    if (gt.dropped && dropped_at < 0) dropped_at = t;

    if (controller.done() && !done_seen) {
      done_seen = true;
      done_at = t;
      if (rep.completed) rep.end_reason = "done";
    }
    if (done_seen && t - done_at >= sc.settle_after_done_s) break;
    if (dropped_at >= 0 && t - dropped_at >= 0.5) {
      rep.end_reason = "dropped";
      break;
    }
  }

  scorer.finish(world.cap().dropped, static_cast<double>(frame) / sc.camera.fps, frame);
  judge_negative_case(rep);
  return result;
}

std::string series_csv(const RunSeries& series) {
  std::string o =
      "t,phase,cycle,cap_place,cap_angle_deg,cap_z_m,cap_yaw_rad,wrist_z_m,wrist_yaw_rad";
  for (const char* tip : {"left", "right"}) {
    for (const char* col : {"x_m", "dy_mm", "fz_meas", "fz_true", "touch", "slip", "true_slip",
                            "over", "tp", "fp", "fn"}) {
      o += fmt::format(",{}_{}", tip, col);
    }
  }
  o += "\n";
  for (const FrameSample& f : series.frames) {
    o += fmt::format("{:.3f},{},{},{},{:.4f},{:.6f},{:.5f},{:.6f},{:.5f}", f.t,
                     control::to_string(static_cast<control::Phase>(f.phase)), f.twist_cycle,
                     to_string(static_cast<CapPlace>(f.cap_place)), f.cap_angle_deg, f.cap_z_m,
                     f.cap_yaw_rad, f.wrist_z_m, f.wrist_yaw_rad);
    for (std::size_t i = 0; i < kFingertips; ++i) {
      o += fmt::format(",{:.6f},{:.5f},{:.4f},{:.4f},{:d},{:d},{:d},{:d},{},{},{}",
                       f.fingertip_x_m[i], f.dy_mm[i], f.max_fz_measured[i], f.max_fz_true[i],
                       f.touch[i], f.slip[i], f.true_slip[i], f.over[i], f.tp[i], f.fp[i], f.fn[i]);
    }
    o += "\n";
  }
  return o;
}

std::string mismatches_csv(const RunSeries& series) {
  std::string o =
      "t,fingertip,element,measured_slip,measured_d_mm,measured_fz,true_sliding,true_fz,"
      "releases,slip_mm,surface_mm,load_ratio,ux_mm,uy_mm,reasons\n";
  for (const Mismatch& m : series.mismatches) {
    o += fmt::format(
        "{:.3f},{},{},{:d},{:.5f},{:.4f},{:d},{:.4f},{},{:.5f},{:.5f},{:.3f},{:.5f},{:.5f},{}\n",
        m.t, m.fingertip, m.element, m.measured_slip, m.measured_d_mm, m.measured_fz,
        m.truth.sliding, m.truth.fz_n, m.truth.releases, m.truth.slip_mm, m.truth.surface_mm,
        m.truth.load_ratio, m.truth.ux_mm, m.truth.uy_mm, m.reasons);
  }
  return o;
}

std::string report_json(const Report& r) {
  using nlohmann::ordered_json;  // keys in the order written: the interface's first
  const auto optional = [](const auto& v) { return v ? ordered_json(*v) : ordered_json(nullptr); };
  const auto precision_recall = [](double precision, double recall) {
    return ordered_json{{"precision", precision}, {"recall", recall}};
  };
  const auto slip_json = [&](const SlipMetrics& m) {
    ordered_json slip = precision_recall(m.precision, m.recall);
    // Nearest-rank percentiles of whole frame counts: whole numbers, written as integers.
    slip["latency_frames_p50"] = std::llround(m.latency_frames_p50);
    slip["latency_frames_p99"] = std::llround(m.latency_frames_p99);
    slip["true_positives"] = m.true_positives;
    slip["false_positives"] = m.false_positives;
    slip["false_negatives"] = m.false_negatives;
    slip["onsets"] = m.onsets;
    slip["missed_onsets"] = m.missed_onsets;
    ordered_json ideal = precision_recall(m.ideal_precision, m.ideal_recall);
    ideal["without_edges"] = precision_recall(m.ideal_precision_clear, m.ideal_recall_clear);
    slip["ideal_sensor"] = std::move(ideal);
    slip["detector"] = m.detector;
    slip["without_edges"] = precision_recall(m.precision_clear, m.recall_clear);
    slip["edge_frames"] = m.edge_frames;
    // Nearest rank of whole frame counts; null without an episode.
    slip["incipient_lead_frames"] =
        m.incipient_episodes > 0 ? ordered_json(std::llround(m.incipient_lead_frames)) : nullptr;
    slip["incipient_episodes"] = m.incipient_episodes;
    slip["incipient_detected"] = m.incipient_detected;
    return slip;
  };
  ordered_json slip = slip_json(r.slip);
  ordered_json latency_ms = nullptr;
  if (r.latency_ms) {
    latency_ms = {
        {"p50", r.latency_ms->p50}, {"p99", r.latency_ms->p99}, {"max", r.latency_ms->max}};
  }
  ordered_json report = {
      {"completed", r.completed},
      {"dropped", r.dropped},
      {"grasp_classified", optional(r.grasp_classified)},
      {"release_classified", optional(r.release_classified)},
      {"recompressions", r.recompressions},
      {"twist_cycles", r.twist_cycles},
      {"tightened_cycle", optional(r.tightened_cycle)},
      {"true_tight_cycle", optional(r.true_tight_cycle)},
      {"max_fz_N", r.max_fz_N},
      {"over_events", r.over_events},
      {"slip", std::move(slip)},
      {"force_rmse_N", {{"normal", r.force_rmse_normal_N}, {"shear", r.force_rmse_shear_N}}},
      {"latency_ms", std::move(latency_ms)},
      {"slip_other", slip_json(r.slip_other)},
      {"lockstep",
       {{"seed", r.seed},
        {"sim_time_s", r.sim_time_s},
        {"frames", r.frames},
        {"physics_step_s", r.physics_step_s},
        {"final_cap_angle_deg", r.final_cap_angle_deg},
        {"normal_full_scale_N", r.normal_full_scale_N},
        {"end_reason", r.end_reason}}},
  };
  // Added after the keys above, which keep their bytes.
  report["tight_time_error_s"] = optional(r.tight_time_error_s);
  report["tight_error_deg"] = optional(r.tight_error_deg);
  report["case"] = r.scenario_case;
  report["negative_case_passed"] = optional(r.negative_case_passed);
  report["opened_in_air"] = r.opened_in_air;
  report["holdable"] = r.hold.holdable;
  report["hold"] = {{"peak_accel_mps2", r.hold.peak_accel_mps2},
                    {"grip_needed_N", r.hold.grip_needed_n},
                    {"grip_allowed_N", r.hold.grip_allowed_n}};
  // Non-finite numbers are written as null; text that is not UTF-8 is replaced, not thrown on.
  return report.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace tactile::rig
