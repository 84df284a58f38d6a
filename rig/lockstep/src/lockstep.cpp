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
#include "tactile/rig/optics.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {
namespace {

// splitmix64: independent seeds for the noise pools and frame offsets from the scenario seed.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

double ratio(std::uint64_t part, std::uint64_t rest) {
  return part + rest > 0 ? static_cast<double>(part) / static_cast<double>(part + rest) : 1.0;
}

}  // namespace

double nearest_rank_percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

void SlipScorer::add(std::size_t i, std::size_t k, std::uint64_t frame, bool predicted,
                     const ElementTruth& et, double thr) {
  m_.true_positives += predicted && et.sliding ? 1 : 0;
  m_.false_positives += predicted && !et.sliding ? 1 : 0;
  m_.false_negatives += !predicted && et.sliding ? 1 : 0;
  Element& es = elements_[i][k];
  const bool ideal =
      et.visible && es.was_visible && std::hypot(et.ux_mm - es.ux_mm, et.uy_mm - es.uy_mm) > thr;
  ideal_tp_ += ideal && et.sliding ? 1 : 0;
  ideal_fp_ += ideal && !et.sliding ? 1 : 0;
  ideal_fn_ += !ideal && et.sliding ? 1 : 0;
  es.was_visible = et.visible;
  es.ux_mm = et.ux_mm;
  es.uy_mm = et.uy_mm;
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
  m_.precision = ratio(m_.true_positives, m_.false_positives);
  m_.recall = ratio(m_.true_positives, m_.false_negatives);
  m_.ideal_precision = ratio(ideal_tp_, ideal_fp_);
  m_.ideal_recall = ratio(ideal_tp_, ideal_fn_);
  m_.latency_frames_p50 = nearest_rank_percentile(latencies_, 0.50);
  m_.latency_frames_p99 = nearest_rank_percentile(latencies_, 0.99);
  out = m_;
}

LockstepResult run_lockstep(const Scenario& sc, const LockstepOptions& opt) {
  LockstepResult result;
  Report& rep = result.report;
  rep.seed = sc.seed;

  const control::Config cfg = scenario_controller_config(sc);
  World world(sc.world);
  const int steps =
      opt.dt_s > 0 ? std::max(1, static_cast<int>(std::lround(1.0 / (sc.camera.fps * opt.dt_s))))
                   : sc.steps_per_frame();
  const double dt = 1.0 / (sc.camera.fps * steps);
  rep.physics_step_s = dt;

  const auto normals = world.element_normals();
  const std::array<const char*, kFingertips> ids{"left", "right"};
  std::vector<Renderer> renderers;
  std::vector<Extractor> extractors;
  std::array<util::Random, kFingertips> frame_rng{util::Random(mix(sc.seed * 4 + 1)),
                                                  util::Random(mix(sc.seed * 4 + 2))};
  std::array<Image, kFingertips> images;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    result.calibrations[i] = make_calibration(ids[i], sc.camera, sc.optics, normals);
    renderers.emplace_back(result.calibrations[i], sc.camera, sc.optics,
                           mix(sc.seed * 4 + 3 + i * 7919));
    ExtractorOptions eo;
    eo.reference_frames = sc.optics.reference_frames;
    extractors.emplace_back(result.calibrations[i], eo);
  }
  const Calibration& cal0 = result.calibrations[0];
  rep.normal_full_scale_N = cal0.normal_curve.y().back();
  TruthRecorder truth(cal0.normal_curve(cal0.contact_on), sc.partial_slip_ratio);

  // The no-load reference, captured before the task starts (nothing touches the sensors).
  std::array<std::array<ElementLoad, kElementsPerFingertip>, kFingertips> loads{};
  for (std::size_t i = 0; i < kFingertips; ++i) {
    extractors[i].begin_reference();
    ReferenceResult r{};
    for (int k = 0; k < sc.optics.reference_frames; ++k) {
      renderers[i].render(loads[i], frame_rng[i], images[i]);
      r = extractors[i].add_reference_frame(images[i].view());
    }
    if (r.status != ReferenceStatus::kComplete) {
      throw std::runtime_error(std::string("lockstep: no-load reference refused: ") +
                               to_string(r.status));
    }
  }

  control::GraspMoveTwistController controller(cfg);
  control::Phase phase = control::Phase::kIdle;
  bool done_seen = false;
  double done_at = 0;
  double dropped_at = -1;
  SlipScorer slip;
  double sq_normal = 0;
  double sq_shear = 0;
  std::uint64_t n_normal = 0;
  std::uint64_t n_shear = 0;
  bool transport_snapshot = false;

  // The paper's Fig. 10 plots against the fingertip's position along the transport: here the
  // horizontal direction from the cap's place to the bottle.
  Vec3 path_dir{sc.world.bottle.x_m - sc.world.cap.x_m, sc.world.bottle.y_m - sc.world.cap.y_m, 0};
  path_dir = norm(path_dir) > 0 ? (1.0 / norm(path_dir)) * path_dir : Vec3{1, 0, 0};

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
    const double thr = cfg.dr_mm * (control::is_twist_phase(phase) ? cfg.twist_dr_factor : 1.0);
    const GroundTruth& gt = truth.take(world, frame, thr);

    // Render and measure both fingertips.
    std::array<control::FingertipInput, control::kFingertips> tips{};
    for (std::size_t i = 0; i < kFingertips; ++i) {
      for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
        const ElementTruth& et = gt.fingertips[i].elements[k];
        loads[i][k] = {et.fz_n, et.ux_mm, et.uy_mm};
      }
      renderers[i].render(loads[i], frame_rng[i], images[i]);
      extractors[i].measure(images[i].view(),
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

    // Score the measurement against the truth, element-frame by element-frame.
    FrameSample sample;
    sample.t = t;
    for (std::size_t i = 0; i < kFingertips; ++i) {
      const auto readings = extractors[i].readings();
      double best = -1;
      for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
        const ElementReading& r = readings[k];
        const ElementTruth& et = gt.fingertips[i].elements[k];
        const double d = std::hypot(r.dx_mm, r.dy_mm);
        const bool predicted = r.contact && r.has_displacement && d > thr;
        slip.add(i, k, frame, predicted, et, thr);
        if (predicted && et.sliding) ++sample.tp[i];
        if (predicted && !et.sliding) ++sample.fp[i];
        if (!predicted && et.sliding) ++sample.fn[i];
        if (opt.record_series && predicted != et.sliding) {
          result.series.mismatches.push_back(
              {t, static_cast<int>(i), static_cast<std::uint32_t>(k), predicted, d, r.fz, et});
        }

        if (et.visible || r.contact) {
          const double en = (r.contact ? r.fz : 0.0) - et.fz_n;
          const double ex = (r.contact ? r.fx : 0.0) - et.fx_n;
          const double ey = (r.contact ? r.fy : 0.0) - et.fy_n;
          sq_normal += en * en;
          sq_shear += ex * ex + ey * ey;
          ++n_normal;
          n_shear += 2;
        }
        if (r.contact) rep.max_fz_N = std::max(rep.max_fz_N, r.fz);
        if (r.contact && r.has_displacement && d > best) {
          best = d;
          sample.dy_mm[i] = r.dy_mm;
        }
        sample.max_fz_measured[i] = std::max(sample.max_fz_measured[i], r.contact ? r.fz : 0.0);
        sample.max_fz_true[i] = std::max(sample.max_fz_true[i], et.fz_n);
        sample.true_slip[i] = sample.true_slip[i] || et.sliding;
      }
      sample.touch[i] = out.flags.fingertip[i].touch;
      sample.slip[i] = out.flags.fingertip[i].slip;
      sample.over[i] = out.flags.fingertip[i].over;
      const Vec3 apex = world.fingertip(i).apex_world;
      sample.fingertip_x_m[i] = apex.x * path_dir.x + apex.y * path_dir.y;
    }
    sample.phase = static_cast<std::uint8_t>(out.phase);
    sample.twist_cycle = out.twist_cycle;
    sample.cap_angle_deg = gt.cap_angle_deg;
    sample.cap_z_m = gt.object_position_m.z;
    sample.wrist_z_m = world.arm().position_m.z;
    sample.wrist_yaw_rad = world.arm().yaw_rad;
    sample.cap_yaw_rad = gt.cap_yaw_rad;
    sample.cap_place = static_cast<std::uint8_t>(gt.place);

    // True tightening: the cycle in which the cap angle first passed free_turn_deg.
    if (gt.cap_tight && !rep.true_tight_cycle) {
      rep.true_tight_cycle = static_cast<int>(out.twist_cycle);
    }

    // Events.
    std::string snapshot_label;
    for (const control::Event& e : out.events) {
      switch (e.kind) {
        case control::EventKind::kGraspClassified:
          if (e.phase == control::Phase::kLift && !rep.grasp_classified) {
            rep.grasp_classified = "grasp";
          } else if (e.phase == control::Phase::kLower && !rep.release_classified) {
            rep.release_classified = "grasp";
          }
          snapshot_label = "grasp classified";
          break;
        case control::EventKind::kReleaseClassified:
          if (e.phase == control::Phase::kLift && !rep.grasp_classified) {
            rep.grasp_classified = "release";
          } else if (e.phase == control::Phase::kLower && !rep.release_classified) {
            rep.release_classified = "release";
          }
          snapshot_label = "release classified";
          break;
        case control::EventKind::kRecompress:
          ++rep.recompressions;
          if (e.phase == control::Phase::kTransport && !transport_snapshot) {
            transport_snapshot = true;
            snapshot_label = "re-compression in transport";
          }
          break;
        case control::EventKind::kOver:
          ++rep.over_events;
          break;
        case control::EventKind::kCapTight:
          if (!rep.tightened_cycle) rep.tightened_cycle = static_cast<int>(e.cycle);
          snapshot_label = "cap tight";
          break;
        case control::EventKind::kDone:
          rep.completed = true;
          break;
        case control::EventKind::kAborted:
          rep.end_reason = std::string("aborted: ") + e.text;
          break;
        default:
          break;
      }
      if (opt.record_series) {
        EventRecord er;
        er.t = t;
        er.kind = static_cast<std::uint8_t>(e.kind);
        er.kind_name = control::to_string(e.kind);
        er.phase = control::to_string(e.phase);
        er.cycle = e.cycle;
        er.fingertip = e.fingertip;
        er.value = e.value;
        er.text = e.text;
        result.series.events.push_back(std::move(er));
      }
    }
    if (opt.record_series) {
      result.series.frames.push_back(sample);
      if (!snapshot_label.empty()) {
        Snapshot snap;
        snap.t = t;
        snap.label = snapshot_label;
        for (std::size_t i = 0; i < kFingertips; ++i) {
          const auto readings = extractors[i].readings();
          for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
            const ElementReading& r = readings[k];
            auto& s = snap.fingertips[i][k];
            s.x_px = result.calibrations[i].elements[k].center_px.x;
            s.y_px = result.calibrations[i].elements[k].center_px.y;
            s.contact = r.contact;
            s.slip = r.contact && r.has_displacement && std::hypot(r.dx_mm, r.dy_mm) > thr;
            s.true_sliding = gt.fingertips[i].elements[k].sliding;
            s.ux_mm = r.ux_mm;
            s.uy_mm = r.uy_mm;
            s.dx_mm = r.dx_mm;
            s.dy_mm = r.dy_mm;
            s.fz_n = r.fz;
          }
        }
        result.series.snapshots.push_back(std::move(snap));
      }
    }

    world.apply(to_world_command(out.command));
    phase = out.phase;
    rep.twist_cycles = static_cast<int>(
        std::max<std::uint32_t>(static_cast<std::uint32_t>(rep.twist_cycles), out.twist_cycle));
    rep.final_cap_angle_deg = gt.cap_angle_deg;
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

  slip.finish(rep.slip);
  rep.dropped = world.cap().dropped;
  rep.frames = frame;
  rep.sim_time_s = static_cast<double>(frame) / sc.camera.fps;
  rep.force_rmse_normal_N = n_normal > 0 ? std::sqrt(sq_normal / static_cast<double>(n_normal)) : 0;
  rep.force_rmse_shear_N = n_shear > 0 ? std::sqrt(sq_shear / static_cast<double>(n_shear)) : 0;
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
      "releases,slip_mm,surface_mm,load_ratio,ux_mm,uy_mm\n";
  for (const Mismatch& m : series.mismatches) {
    o += fmt::format(
        "{:.3f},{},{},{:d},{:.5f},{:.4f},{:d},{:.4f},{},{:.5f},{:.5f},{:.3f},{:.5f},{:.5f}\n", m.t,
        m.fingertip, m.element, m.measured_slip, m.measured_d_mm, m.measured_fz, m.truth.sliding,
        m.truth.fz_n, m.truth.releases, m.truth.slip_mm, m.truth.surface_mm, m.truth.load_ratio,
        m.truth.ux_mm, m.truth.uy_mm);
  }
  return o;
}

std::string report_json(const Report& r) {
  using nlohmann::ordered_json;  // keys in the order written: the interface's first
  const auto optional = [](const auto& v) { return v ? ordered_json(*v) : ordered_json(nullptr); };
  const auto precision_recall = [](double precision, double recall) {
    return ordered_json{{"precision", precision}, {"recall", recall}};
  };
  ordered_json slip = precision_recall(r.slip.precision, r.slip.recall);
  // Nearest-rank percentiles of whole frame counts: whole numbers, written as integers.
  slip["latency_frames_p50"] = std::llround(r.slip.latency_frames_p50);
  slip["latency_frames_p99"] = std::llround(r.slip.latency_frames_p99);
  slip["true_positives"] = r.slip.true_positives;
  slip["false_positives"] = r.slip.false_positives;
  slip["false_negatives"] = r.slip.false_negatives;
  slip["onsets"] = r.slip.onsets;
  slip["missed_onsets"] = r.slip.missed_onsets;
  slip["ideal_sensor"] = precision_recall(r.slip.ideal_precision, r.slip.ideal_recall);
  ordered_json latency_ms = nullptr;
  if (r.latency_ms) {
    latency_ms = {
        {"p50", r.latency_ms->p50}, {"p99", r.latency_ms->p99}, {"max", r.latency_ms->max}};
  }
  const ordered_json report = {
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
      {"lockstep",
       {{"seed", r.seed},
        {"sim_time_s", r.sim_time_s},
        {"frames", r.frames},
        {"physics_step_s", r.physics_step_s},
        {"final_cap_angle_deg", r.final_cap_angle_deg},
        {"normal_full_scale_N", r.normal_full_scale_N},
        {"end_reason", r.end_reason}}},
  };
  // Non-finite numbers are written as null; text that is not UTF-8 is replaced, not thrown on.
  return report.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace tactile::rig
