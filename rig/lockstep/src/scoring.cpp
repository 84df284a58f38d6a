#include "tactile/rig/scoring.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace tactile::rig {

double slip_threshold_mm(const control::Config& cfg, control::Phase phase) {
  return control::FlagAnalyzer(cfg).dr(control::is_twist_phase(phase));
}

Vec3 transport_direction(const WorldParams& w) {
  const Vec3 d{w.bottle.x_m - w.cap.x_m, w.bottle.y_m - w.cap.y_m, 0};
  return norm(d) > 0 ? (1.0 / norm(d)) * d : Vec3{1, 0, 0};
}

FramePose frame_pose(const World& world, Vec3 transport) {
  FramePose p;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    const Vec3 apex = world.fingertip(i).apex_world;
    p.fingertip_x_m[i] = apex.x * transport.x + apex.y * transport.y;
  }
  p.wrist_z_m = world.arm().position_m.z;
  p.wrist_yaw_rad = world.arm().yaw_rad;
  return p;
}

namespace {

control::SlipDetectorKind other(control::SlipDetectorKind k) {
  // The learned combiner beside the rules it combines; the field detector beside the paper's.
  switch (k) {
    case control::SlipDetectorKind::kPaper:
      return control::SlipDetectorKind::kField;
    case control::SlipDetectorKind::kField:
      return control::SlipDetectorKind::kPaper;
    case control::SlipDetectorKind::kLearned:
      return control::SlipDetectorKind::kField;
  }
  return control::SlipDetectorKind::kPaper;
}

}  // namespace

void IncipientLead::add(std::size_t fingertip, std::uint64_t frame, const FingertipTruth& truth,
                        const std::array<const control::FingertipSlip*, 2>& decided,
                        std::size_t elements) {
  std::size_t in_contact = 0;
  std::size_t sliding = 0;
  for (const ElementTruth& et : truth.elements) {
    in_contact += et.contact ? 1 : 0;
    sliding += et.contact && et.sliding ? 1 : 0;
  }
  const bool gross = in_contact > 0 && 2 * sliding > in_contact;
  const bool partial = sliding > 0 && !gross;
  Tip& tip = tips_[fingertip];
  if (gross && tip.in_run_up) {
    for (std::size_t d = 0; d < 2; ++d) {
      const auto& first = tip.first_flag[d];
      leads_[d].push_back(first ? static_cast<double>(frame - *first) : 0.0);
    }
  }
  if (!partial) {
    tip = Tip{};
    return;
  }
  tip.in_run_up = true;
  for (std::size_t d = 0; d < 2; ++d) {
    if (tip.first_flag[d]) continue;
    const std::size_t n = std::min(elements, kElementsPerFingertip);
    for (std::size_t k = 0; k < n; ++k) {
      if (control::slipping(decided[d]->state[k])) {
        tip.first_flag[d] = frame;
        break;
      }
    }
  }
}

void IncipientLead::finish(std::size_t d, SlipMetrics& m) const {
  const std::vector<double>& leads = leads_[d];
  m.incipient_lead_frames = nearest_rank_percentile(leads, 0.5);
  m.incipient_episodes = leads.size();
  m.incipient_detected = static_cast<std::uint64_t>(
      std::count_if(leads.begin(), leads.end(), [](double v) { return v > 0; }));
}

void steady_need(std::span<const double> t, std::span<const double> need, double half_window_s,
                 std::span<double> steady) {
  // Two pointers over the ascending times; a window holds a few dozen frames, so each frame
  // scans its own window. The nanosecond keeps a frame exactly 0.1 s away (frame / fps) in.
  const double reach = half_window_s + 1e-9;
  std::size_t first = 0;
  std::size_t last = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    while (t[k] - t[first] > reach)
      ++first;
    while (last + 1 < t.size() && t[last + 1] - t[k] <= reach)
      ++last;
    steady[k] = *std::max_element(need.begin() + static_cast<std::ptrdiff_t>(first),
                                  need.begin() + static_cast<std::ptrdiff_t>(last) + 1);
  }
}

void GripScorer::reserve(std::size_t frames) {
  t_.reserve(frames);
  need_.reserve(frames);
  applied_.reserve(frames);
  held_.reserve(frames);
}

void GripScorer::add(double t, const GripTruth& g) {
  t_.push_back(t);
  need_.push_back(g.needed_n);
  applied_.push_back(g.scored_n());
  held_.push_back(g.held ? 1 : 0);
  if (g.held) slide_mm_ += g.slide_mm;
}

GripMetrics GripScorer::finish() {
  GripMetrics m;
  m.cap_slide_carry_mm = slide_mm_;
  std::vector<double> steady(t_.size());
  steady_need(t_, need_, kSteadyGripHalfWindowS, steady);
  std::vector<double> ratio, instant, applied;
  for (std::size_t k = 0; k < t_.size(); ++k) {
    if (held_[k] == 0) continue;
    ratio.push_back(applied_[k] / steady[k]);
    instant.push_back(applied_[k] / need_[k]);
    applied.push_back(applied_[k]);
    m.steady_need_max_N = std::max(m.steady_need_max_N, steady[k]);
  }
  m.held_frames = ratio.size();
  m.ratio_p50 = nearest_rank_percentile(ratio, 0.50);
  m.ratio_p95 = nearest_rank_percentile(ratio, 0.95);
  m.ratio_max = nearest_rank_percentile(ratio, 1.0);
  m.instant_ratio_p50 = nearest_rank_percentile(instant, 0.50);
  m.instant_ratio_p95 = nearest_rank_percentile(instant, 0.95);
  m.applied_p50_N = nearest_rank_percentile(applied, 0.50);
  return m;
}

RunScorer::RunScorer(LockstepResult& run, const control::Config& cfg, bool record_series)
    : run_(run),
      cfg_(cfg),
      flags_(cfg),
      tighten_yaw_sign_(cfg.tighten_clockwise ? -1.0 : 1.0),
      record_(record_series),
      measured_{control::SlipDetector(cfg.slip_detector, cfg),
                control::SlipDetector(other(cfg.slip_detector), cfg)},
      ideal_{control::SlipDetector(cfg.slip_detector, cfg),
             control::SlipDetector(other(cfg.slip_detector), cfg)} {
  const Calibration& cal = run.calibrations[0];
  run_.report.normal_full_scale_N = cal.normal_curve.y().back();
  run_.report.slip.detector = control::to_string(cfg.slip_detector);
  run_.report.slip_other.detector = control::to_string(other(cfg.slip_detector));
  run_.report.controller = {control::to_string(cfg.slip_detector), control::to_string(cfg.grip)};
}

FrameSample* RunScorer::sample_for(std::uint64_t frame) {
  auto& frames = run_.series.frames;
  for (std::size_t n = 0; n < std::min<std::size_t>(frames.size(), 128); ++n) {
    FrameSample& s = frames[frames.size() - 1 - n];
    if (s.frame == frame) return &s;
  }
  return nullptr;
}

void RunScorer::add_truth(std::uint64_t frame, double t, const GroundTruth& gt,
                          const ControllerState& controller, const FramePose& pose) {
  Report& rep = run_.report;
  if (have_wrist_yaw_) {
    const double turn =
        tighten_yaw_sign_ * (pose.wrist_yaw_rad - last_wrist_yaw_rad_) * 180.0 / std::numbers::pi;
    wrist_turn_deg_ += std::max(turn, 0.0);
  }
  have_wrist_yaw_ = true;
  last_wrist_yaw_rad_ = pose.wrist_yaw_rad;
  // True tightening: the controller's cycle when the cap angle first passed free_turn_deg.
  if (gt.cap_tight && !rep.true_tight_cycle) {
    rep.true_tight_cycle = static_cast<int>(controller.twist_cycle);
  }
  if (gt.cap_tight && !cap_stop_) cap_stop_ = Moment{t, wrist_turn_deg_};
  rep.twist_cycles = std::max(rep.twist_cycles, static_cast<int>(controller.twist_cycle));
  rep.final_cap_angle_deg = gt.cap_angle_deg;
  if (!record_) return;
  FrameSample s;
  s.frame = frame;
  s.t = t;
  s.phase = static_cast<std::uint8_t>(controller.phase);
  s.twist_cycle = controller.twist_cycle;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    for (const ElementTruth& et : gt.fingertips[i].elements) {
      s.max_fz_true[i] = std::max(s.max_fz_true[i], et.fz_n);
      s.true_slip[i] = s.true_slip[i] || et.sliding;
    }
  }
  s.fingertip_x_m = pose.fingertip_x_m;
  s.wrist_z_m = pose.wrist_z_m;
  s.wrist_yaw_rad = pose.wrist_yaw_rad;
  s.cap_angle_deg = gt.cap_angle_deg;
  s.cap_z_m = gt.object_position_m.z;
  s.cap_yaw_rad = gt.cap_yaw_rad;
  s.cap_place = static_cast<std::uint8_t>(gt.place);
  run_.series.frames.push_back(s);
}

void RunScorer::add_grip(double t, const GripTruth& grip) {
  grip_.add(t, grip);
  crush_.add(t, grip);
  if (!record_ || run_.series.frames.empty()) return;
  FrameSample& s = run_.series.frames.back();  // add_truth's sample of the same frame
  s.grip_need_n = grip.needed_n;
  s.grip_applied_n = grip.scored_n();
  s.grip_held = grip.held;
}

void RunScorer::add_measurement(std::size_t i, std::uint64_t frame,
                                std::span<const ElementReading> readings,
                                const FingertipTruth& truth, control::Phase phase,
                                const control::ArmMotion& arm) {
  Report& rep = run_.report;
  const bool twist = control::is_twist_phase(phase);
  const double thr = flags_.dr(twist);
  FrameSample* sample = record_ ? sample_for(frame) : nullptr;
  const double t = sample != nullptr ? sample->t : 0.0;

  // The ideal sensor: what the truth says each element reads, its displacement the change of
  // its true shear displacement since the last frame.
  IdealTip& it = ideal_tips_[i];
  for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
    const ElementTruth& et = truth.elements[k];
    ElementReading& r = it.readings[k];
    r = ElementReading{};
    r.id = static_cast<std::uint32_t>(k);
    r.x_px = run_.calibrations[i].elements[k].center_px.x;
    r.y_px = run_.calibrations[i].elements[k].center_px.y;
    r.contact = et.visible;
    r.has_displacement = et.visible && it.was_visible[k];
    if (et.visible) {
      r.ux_mm = et.ux_mm;
      r.uy_mm = et.uy_mm;
      r.fx = et.fx_n;
      r.fy = et.fy_n;
      r.fz = et.fz_n;
    }
    if (r.has_displacement) {
      r.dx_mm = et.ux_mm - it.ux_mm[k];
      r.dy_mm = et.uy_mm - it.uy_mm[k];
    }
    it.was_visible[k] = et.visible;
    it.ux_mm[k] = et.ux_mm;
    it.uy_mm[k] = et.uy_mm;
  }
  control::FingertipInput measured_in;
  measured_in.elements = readings;
  measured_in.fresh = true;
  measured_in.camera_timestamp_ns = truth.camera_timestamp_ns;
  control::FingertipInput ideal_in;
  ideal_in.elements = it.readings;
  ideal_in.fresh = true;
  ideal_in.camera_timestamp_ns = truth.camera_timestamp_ns;
  std::array<const control::FingertipSlip*, 2> decided{};
  for (std::size_t d = 0; d < 2; ++d) {
    decided[d] = &measured_[d].update(i, measured_in, thr, arm);
    const control::FingertipSlip& ideal = ideal_[d].update(i, ideal_in, thr, arm);
    for (std::size_t k = 0; k < kElementsPerFingertip && k < readings.size(); ++k) {
      slip_[d].add(i, k, frame, control::slipping(decided[d]->state[k]),
                   control::slipping(ideal.state[k]), truth.elements[k], thr);
    }
  }
  lead_.add(i, frame, truth, decided, readings.size());
  const control::FingertipSlip& run_slip = *decided[0];
  if (feature_log_ != nullptr) {
    (void)recorder_->update(i, measured_in, thr, arm);  // its signals, below
    const auto& has = recorder_->has_features(i);
    for (std::size_t k = 0; k < kElementsPerFingertip && k < readings.size(); ++k) {
      if (!has[k]) continue;
      const control::SlipFeatures x = recorder_->features(i, k);
      const bool label = truth.elements[k].sliding;
      // Every length and the load below half their thresholds, and no reason of the field
      // rules (not the compiled-in model's decision, so the rows do not depend on the model
      // being replaced).
      const auto at = [&x](control::SlipSignal s) { return x[control::column(s)]; };
      const bool easy =
          !label && at(control::SlipSignal::kFieldReasons) == 0.0f &&
          at(control::SlipSignal::kMovedDr) < 0.5f && at(control::SlipSignal::kDepartedDr) < 0.5f &&
          at(control::SlipSignal::kSurfaceDr) < 0.5f && at(control::SlipSignal::kLoad) < 0.5f;
      if (easy && easy_seen_++ % kSlipFeatureEasyStride != 0) continue;
      feature_log_->x.push_back(x);
      feature_log_->label.push_back(label ? 1 : 0);
      feature_log_->weight.push_back(easy ? static_cast<float>(kSlipFeatureEasyStride) : 1.0f);
    }
  }

  Latest& latest = latest_[i];
  double best = -1;
  for (std::size_t k = 0; k < kElementsPerFingertip && k < readings.size(); ++k) {
    const ElementReading& r = readings[k];
    const ElementTruth& et = truth.elements[k];
    const bool predicted = control::slipping(run_slip.state[k]);
    latest.readings[k] = r;
    latest.true_sliding[k] = et.sliding;
    latest.slip[k] = predicted;
    const double d = std::hypot(r.dx_mm, r.dy_mm);
    if (sample != nullptr) {
      if (predicted && et.sliding) ++sample->tp[i];
      if (predicted && !et.sliding) ++sample->fp[i];
      if (!predicted && et.sliding) ++sample->fn[i];
    }
    if (record_ && predicted != et.sliding) {
      run_.series.mismatches.push_back({t, static_cast<int>(i), static_cast<std::uint32_t>(k),
                                        predicted, d, r.fz, run_slip.reasons[k], et});
    }
    if (et.visible || r.contact) {
      const double en = (r.contact ? r.fz : 0.0) - et.fz_n;
      const double ex = (r.contact ? r.fx : 0.0) - et.fx_n;
      const double ey = (r.contact ? r.fy : 0.0) - et.fy_n;
      sq_normal_[i] += en * en;
      sq_shear_[i] += ex * ex + ey * ey;
      ++n_normal_;
      n_shear_ += 2;
    }
    if (r.contact) rep.max_fz_N = std::max(rep.max_fz_N, r.fz);
    if (sample != nullptr) {
      if (r.contact && r.has_displacement && d > best) {
        best = d;
        sample->dy_mm[i] = r.dy_mm;
      }
      sample->max_fz_measured[i] = std::max(sample->max_fz_measured[i], r.contact ? r.fz : 0.0);
    }
  }
  if (sample != nullptr) {
    // TOUCH, SLIP and OVER as the controller's FlagAnalyzer decides them from this frame.
    const control::FingertipFlags f = flags_.analyze(measured_in, run_slip);
    sample->touch[i] = f.touch;
    sample->slip[i] = f.slip;
    sample->over[i] = f.over;
  }
}

void RunScorer::log_features(SlipFeatureLog* log) {
  feature_log_ = log;
  recorder_.emplace(control::SlipDetectorKind::kLearned, cfg_);
}

void RunScorer::snapshot(double t, const char* label) {
  auto& snapshots = run_.series.snapshots;
  // One snapshot per moment: a later event of the same moment names it.
  if (!snapshots.empty() && snapshots.back().t == t) snapshots.pop_back();
  Snapshot snap;
  snap.t = t;
  snap.label = label;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    const Latest& latest = latest_[i];
    for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
      const ElementReading& r = latest.readings[k];
      auto& s = snap.fingertips[i][k];
      s.x_px = run_.calibrations[i].elements[k].center_px.x;
      s.y_px = run_.calibrations[i].elements[k].center_px.y;
      s.contact = r.contact;
      s.slip = latest.slip[k];
      s.true_sliding = latest.true_sliding[k];
      s.ux_mm = r.ux_mm;
      s.uy_mm = r.uy_mm;
      s.dx_mm = r.dx_mm;
      s.dy_mm = r.dy_mm;
      s.fz_n = r.fz;
    }
  }
  snapshots.push_back(std::move(snap));
}

void RunScorer::add_event(const control::Event& e, double t) {
  Report& rep = run_.report;
  const char* label = nullptr;
  const auto classified = [&rep, &e](const char* as) {
    if (e.phase == control::Phase::kLift && !rep.grasp_classified) rep.grasp_classified = as;
    if (e.phase == control::Phase::kLower && !rep.release_classified) rep.release_classified = as;
  };
  switch (e.kind) {
    case control::EventKind::kGraspClassified:
      classified("grasp");
      label = "grasp classified";
      break;
    case control::EventKind::kReleaseClassified:
      classified("release");
      label = "release classified";
      break;
    case control::EventKind::kRecompress:
      ++rep.recompressions;
      if (const auto p = static_cast<std::size_t>(e.phase); p < kPhaseCount)
        ++rep.recompressions_by_phase[p];
      if (e.phase == control::Phase::kTransport && !transport_snapshot_) {
        transport_snapshot_ = true;
        label = "re-compression in transport";
      }
      break;
    case control::EventKind::kOver:
      ++rep.over_events;
      break;
    case control::EventKind::kCapTight:
      if (!rep.tightened_cycle) rep.tightened_cycle = static_cast<int>(e.cycle);
      if (!declared_tight_) declared_tight_ = Moment{t, wrist_turn_deg_};
      label = "cap tight";
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
  rep.twist_cycles = std::max(rep.twist_cycles, static_cast<int>(e.cycle));
  if (!record_) return;
  EventRecord er;
  er.t = t;
  er.kind = static_cast<std::uint8_t>(e.kind);
  er.kind_name = control::to_string(e.kind);
  er.phase = control::to_string(e.phase);
  er.cycle = e.cycle;
  er.fingertip = e.fingertip;
  er.value = e.value;
  er.text = e.text;
  run_.series.events.push_back(std::move(er));
  if (label != nullptr) snapshot(t, label);
}

void RunScorer::finish(bool dropped, double sim_time_s, std::uint64_t frames) {
  Report& rep = run_.report;
  slip_[0].finish(rep.slip);
  slip_[1].finish(rep.slip_other);
  lead_.finish(0, rep.slip);
  lead_.finish(1, rep.slip_other);
  rep.grip = grip_.finish();
  // A crushed cap is said by `fragile.broken` alone: `completed` and the negative cases stay the
  // controller's decisions, so that they compare across grips and draws (docs/rig.md).
  if (crush_.crush_force_n > 0) rep.fragile = crush_;
  if (cap_stop_ && declared_tight_) {
    rep.tight_time_error_s = declared_tight_->t - cap_stop_->t;
    rep.tight_error_deg = declared_tight_->wrist_turn_deg - cap_stop_->wrist_turn_deg;
  }
  rep.dropped = dropped;
  rep.frames = frames;
  rep.sim_time_s = sim_time_s;
  double sq_normal = 0;
  double sq_shear = 0;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    sq_normal += sq_normal_[i];
    sq_shear += sq_shear_[i];
  }
  rep.force_rmse_normal_N =
      n_normal_ > 0 ? std::sqrt(sq_normal / static_cast<double>(n_normal_)) : 0;
  rep.force_rmse_shear_N = n_shear_ > 0 ? std::sqrt(sq_shear / static_cast<double>(n_shear_)) : 0;
}

}  // namespace tactile::rig
