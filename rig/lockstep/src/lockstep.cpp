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
#include "tactile/rig/scenario_run.hpp"
#include "tactile/rig/scoring.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/rig/world.hpp"
#include "tactile/util/percentile.hpp"

namespace tactile::rig {
namespace {

double ratio(std::uint64_t part, std::uint64_t rest) {
  return part + rest > 0 ? static_cast<double>(part) / static_cast<double>(part + rest) : 1.0;
}

// The report's `grip`: the ratios are null without a held frame.
nlohmann::ordered_json grip_json(const GripMetrics& g) {
  using nlohmann::ordered_json;
  const auto held = [&g](double v) { return g.held_frames > 0 ? ordered_json(v) : nullptr; };
  return {{"ratio_p50", held(g.ratio_p50)},
          {"ratio_p95", held(g.ratio_p95)},
          {"ratio_max", held(g.ratio_max)},
          {"instant_ratio_p50", held(g.instant_ratio_p50)},
          {"instant_ratio_p95", held(g.instant_ratio_p95)},
          {"cap_slide_carry_mm", g.cap_slide_carry_mm},
          {"held_frames", g.held_frames},
          {"applied_p50_N", held(g.applied_p50_N)},
          {"steady_need_max_N", held(g.steady_need_max_N)}};
}

nlohmann::ordered_json vec_json(Vec3 v) {
  return nlohmann::ordered_json::array({v.x, v.y, v.z});
}

// A start on the run's clock; null while its stage never came.
nlohmann::ordered_json start_json(double start_s) {
  return std::isfinite(start_s) ? nlohmann::ordered_json(start_s) : nullptr;
}

// The report's `disturbance`: each disturbance the scenario set, as applied.
nlohmann::ordered_json disturbance_json(const DisturbanceParams& d) {
  using nlohmann::ordered_json;
  ordered_json out = ordered_json::object();
  if (d.pull.force_n > 0) {
    out["pull"] = {{"force_N", d.pull.force_n},
                   {"direction", vec_json(d.pull.direction)},
                   {"start_s", start_json(d.pull.start_s)},
                   {"ramp_s", d.pull.ramp_s},
                   {"duration_s", std::isfinite(d.pull.duration_s) ? ordered_json(d.pull.duration_s)
                                                                   : ordered_json(nullptr)}};
  }
  if (d.mass_step.added_kg > 0) {
    out["mass_step"] = {{"added_kg", d.mass_step.added_kg},
                        {"start_s", start_json(d.mass_step.start_s)}};
  }
  if (d.knock.impulse_ns > 0) {
    out["knock"] = {{"impulse_Ns", d.knock.impulse_ns},
                    {"direction", vec_json(d.knock.direction)},
                    {"start_s", start_json(d.knock.start_s)},
                    {"duration_s", d.knock.duration_s}};
  }
  return out;
}

// The report's `fragile`.
nlohmann::ordered_json fragile_json(const CrushTruth& c) {
  using nlohmann::ordered_json;
  return {{"crush_force_N", c.crush_force_n},
          {"broken", c.broken},
          {"broken_at_s", c.broken ? ordered_json(c.broken_at_s) : ordered_json(nullptr)},
          {"peak_grip_N", c.peak_grip_n},
          {"peak_over_crush", c.peak_grip_n / c.crush_force_n}};
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

LockstepResult run_lockstep(const Scenario& sc, const LockstepOptions& opt) {
  LockstepResult result;
  // Only the measurement sees these images, and it reads only the disks: no live background.
  CameraParams camera = sc.camera;
  camera.live_background = false;
  ScenarioRun run(sc, camera, result, opt.record_series);
  if (opt.slip_features != nullptr) run.scorer().log_features(opt.slip_features);
  const int steps =
      opt.dt_s > 0 ? std::max(1, static_cast<int>(std::lround(1.0 / (sc.camera.fps * opt.dt_s))))
                   : sc.steps_per_frame();
  const double dt = 1.0 / (sc.camera.fps * steps);
  result.report.physics_step_s = dt;

  const auto normals = run.world().element_normals();
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
      r = extractors[i].add_reference_frame(run.sensors().render(i, FingertipTruth{}).view());
    if (r.status != ReferenceStatus::kComplete) {
      throw std::runtime_error(std::string("lockstep: no-load reference refused: ") +
                               to_string(r.status));
    }
  }

  control::GraspMoveTwistController controller(run.config());
  control::Phase phase = control::Phase::kIdle;
  std::uint64_t frame = 0;
  do {
    if (!run.step(steps, dt)) break;
    ++frame;
    const double t = static_cast<double>(frame) / sc.camera.fps;
    // A copy (fixed arrays, no allocation): the truth's displacement is then the image's own.
    GroundTruth gt = run.take_truth(frame, phase);

    // Render and measure both fingertips.
    control::ControllerInput in{};
    for (std::size_t i = 0; i < kFingertips; ++i) {
      extractors[i].measure(run.sensors().render(i, gt.fingertips[i]).view(),
                            {frame, static_cast<std::int64_t>(std::llround(t * 1e9))});
      run.sensors().image_truth(i, gt.fingertips[i]);
      control::FingertipInput& tip = in.fingertips[i];
      tip.elements = extractors[i].readings();
      tip.normals = normals;
      tip.sequence = frame;
      tip.camera_timestamp_ns = std::llround(t * 1e9);
      tip.fresh = true;
      tip.stale = false;
    }
    in.arm = arm_feedback(run.world());
    in.now_s = t;
    const control::ControllerOutput out = controller.update(in);
    // The arm's motion as the controller saw it, for the scorer's detectors.
    const control::ArmMotion arm = run.arm_motion(in.now_s);

    run.score_truth(frame, t, gt, {out.phase, out.twist_cycle});
    for (std::size_t i = 0; i < kFingertips; ++i)
      run.scorer().add_measurement(i, frame, extractors[i].readings(), gt.fingertips[i], phase,
                                   arm);
    for (const control::Event& e : out.events)
      run.scorer().add_event(e, t);

    run.apply(out.command);
    phase = out.phase;
    if (controller.done()) run.task_ended(t);
  } while (!run.ended_after_frame(frame, static_cast<double>(frame) / sc.camera.fps));

  run.finish(static_cast<double>(frame) / sc.camera.fps, frame);
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
  o += ",grip_need_N,grip_applied_N,grip_held\n";
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
    o += fmt::format(",{:.4f},{:.4f},{:d}\n", f.grip_need_n, f.grip_applied_n, f.grip_held);
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
  report["controller"] = {{"slip_detector", r.controller.slip_detector},
                          {"grip", r.controller.grip}};
  report["grip"] = grip_json(r.grip);
  ordered_json by_stage = ordered_json::object();
  for (std::size_t p = 0; p < kPhaseCount; ++p) {
    if (r.recompressions_by_phase[p] > 0)
      by_stage[control::to_string(static_cast<control::Phase>(p))] = r.recompressions_by_phase[p];
  }
  report["recompressions_by_stage"] = std::move(by_stage);
  // Only for a scenario with them: every other report keeps its bytes.
  if (r.disturbance) report["disturbance"] = disturbance_json(*r.disturbance);
  if (r.fragile) report["fragile"] = fragile_json(*r.fragile);
  if (r.sensor) {
    report["sensor"] = {{"calibration", r.sensor->calibration},
                        {"image",
                         {{"width", r.sensor->width},
                          {"height", r.sensor->height},
                          {"bit_depth", r.sensor->bit_depth}}}};
  }
  ordered_json machine = nullptr;
  if (r.machine) {
    machine = {{"cpu_steal_pct", r.machine->steal_pct},
               {"load_average_1m", r.machine->load_average_1m},
               {"cores", r.machine->cores},
               {"explains_latency", util::explains_latency(*r.machine)}};
  }
  report["machine"] = std::move(machine);
  // Non-finite numbers are written as null; text that is not UTF-8 is replaced, not thrown on.
  return report.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace tactile::rig
