#include "tactile/rig/scoring.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace tactile::rig {
RunScorer::RunScorer(LockstepResult& run, const control::Config& cfg, bool record_series)
    : run_(run), cfg_(cfg), record_(record_series) {
  const Calibration& cal = run.calibrations[0];
  run_.report.normal_full_scale_N = cal.normal_curve.y().back();
}

FrameSample* RunScorer::sample_for(double t) {
  auto& frames = run_.series.frames;
  for (std::size_t n = 0; n < std::min<std::size_t>(frames.size(), 128); ++n) {
    FrameSample& s = frames[frames.size() - 1 - n];
    if (std::abs(s.t - t) < 1e-9) return &s;
  }
  return nullptr;
}

void RunScorer::add_truth(const GroundTruth& gt, std::uint32_t twist_cycle) {
  Report& rep = run_.report;
  if (gt.cap_tight && !rep.true_tight_cycle) rep.true_tight_cycle = static_cast<int>(twist_cycle);
  rep.final_cap_angle_deg = gt.cap_angle_deg;
  if (!record_) return;
  FrameSample s;
  s.t = gt.sim_time_s;
  s.twist_cycle = twist_cycle;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    for (const ElementTruth& et : gt.fingertips[i].elements) {
      s.max_fz_true[i] = std::max(s.max_fz_true[i], et.fz_n);
      s.true_slip[i] = s.true_slip[i] || et.sliding;
    }
  }
  s.cap_angle_deg = gt.cap_angle_deg;
  s.cap_z_m = gt.object_position_m.z;
  s.cap_yaw_rad = gt.cap_yaw_rad;
  s.cap_place = static_cast<std::uint8_t>(gt.place);
  run_.series.frames.push_back(s);
}

void RunScorer::add_measurement(std::size_t i, std::uint64_t frame, double t,
                                std::span<const ElementReading> readings,
                                const FingertipTruth& truth, double thr, const World& world) {
  Report& rep = run_.report;
  FrameSample* sample = record_ ? sample_for(t) : nullptr;
  double best = -1;
  for (std::size_t k = 0; k < kElementsPerFingertip && k < readings.size(); ++k) {
    const ElementReading& r = readings[k];
    const ElementTruth& et = truth.elements[k];
    const double d = std::hypot(r.dx_mm, r.dy_mm);
    const bool predicted = r.contact && r.has_displacement && d > thr;
    slip_.add(i, k, frame, predicted, et, thr);
    if (sample != nullptr) {
      if (predicted && et.sliding) ++sample->tp[i];
      if (predicted && !et.sliding) ++sample->fp[i];
      if (!predicted && et.sliding) ++sample->fn[i];
    }
    if (record_ && predicted != et.sliding) {
      run_.series.mismatches.push_back(
          {t, static_cast<int>(i), static_cast<std::uint32_t>(k), predicted, d, r.fz, et});
    }
    if (et.visible || r.contact) {
      const double en = (r.contact ? r.fz : 0.0) - et.fz_n;
      const double ex = (r.contact ? r.fx : 0.0) - et.fx_n;
      const double ey = (r.contact ? r.fy : 0.0) - et.fy_n;
      sq_normal_ += en * en;
      sq_shear_ += ex * ex + ey * ey;
      ++n_normal_;
      n_shear_ += 2;
    }
    if (r.contact) rep.max_fz_N = std::max(rep.max_fz_N, r.fz);
    if (sample != nullptr) {
      if (r.contact && r.has_displacement && d > best) {
        best = d;
        sample->dy_mm[i] = r.dy_mm;
      }
      const double fz = r.contact ? r.fz : 0.0;
      sample->max_fz_measured[i] = std::max(sample->max_fz_measured[i], fz);
      sample->touch[i] = sample->touch[i] || fz > cfg_.f1_n || predicted;
      sample->over[i] = sample->over[i] || fz > cfg_.f2_n;
      sample->slip[i] = sample->slip[i] || predicted;
    }
  }
  if (sample != nullptr) {
    sample->fingertip_x_m[i] = world.fingertip(i).apex_world.x;
    sample->wrist_z_m = world.arm().position_m.z;
    sample->wrist_yaw_rad = world.arm().yaw_rad;
  }
}

void RunScorer::add_event(control::EventKind kind, control::Phase phase, std::uint32_t cycle,
                          std::string_view text, double value, double t) {
  Report& rep = run_.report;
  switch (kind) {
    case control::EventKind::kGraspClassified:
      if (phase == control::Phase::kLift && !rep.grasp_classified) rep.grasp_classified = "grasp";
      if (phase == control::Phase::kLower && !rep.release_classified)
        rep.release_classified = "grasp";
      break;
    case control::EventKind::kReleaseClassified:
      if (phase == control::Phase::kLift && !rep.grasp_classified) rep.grasp_classified = "release";
      if (phase == control::Phase::kLower && !rep.release_classified)
        rep.release_classified = "release";
      break;
    case control::EventKind::kRecompress:
      ++rep.recompressions;
      break;
    case control::EventKind::kOver:
      ++rep.over_events;
      break;
    case control::EventKind::kCapTight:
      if (!rep.tightened_cycle) rep.tightened_cycle = static_cast<int>(cycle);
      break;
    case control::EventKind::kDone:
      rep.completed = true;
      break;
    case control::EventKind::kAborted:
      rep.end_reason = "aborted: " + std::string(text);
      break;
    default:
      break;
  }
  rep.twist_cycles = std::max(rep.twist_cycles, static_cast<int>(cycle));
  if (record_) {
    EventRecord er;
    er.t = t;
    er.kind = static_cast<std::uint8_t>(kind);
    er.kind_name = control::to_string(kind);
    er.phase = control::to_string(phase);
    er.cycle = cycle;
    er.value = value;
    er.text = std::string(text);
    run_.series.events.push_back(std::move(er));
  }
}

void RunScorer::finish(const World& world, double sim_time_s, std::uint64_t frames) {
  Report& rep = run_.report;
  slip_.finish(rep.slip);
  rep.dropped = world.cap().dropped;
  rep.frames = frames;
  rep.sim_time_s = sim_time_s;
  rep.force_rmse_normal_N =
      n_normal_ > 0 ? std::sqrt(sq_normal_ / static_cast<double>(n_normal_)) : 0;
  rep.force_rmse_shear_N = n_shear_ > 0 ? std::sqrt(sq_shear_ / static_cast<double>(n_shear_)) : 0;
}

}  // namespace tactile::rig
