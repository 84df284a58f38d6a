#include "tactile/control/slip_detector.hpp"

#include <algorithm>
#include <cmath>

#include "field_rules.hpp"
#include "learned_signals.hpp"

namespace tactile::control {

namespace {

std::size_t element_count(const FingertipInput& in) {
  return std::min(in.elements.size(), kMaxSlipElements);
}

}  // namespace

SlipFeatures SlipDetector::features(std::size_t fingertip, std::size_t element) const noexcept {
  SlipFeatures x{};
  if (!has_features_[fingertip][element]) return x;
  const std::size_t e = column_of_[fingertip][element];
  for (std::size_t k = 0; k < kSlipFeatures; ++k)
    x[k] = columns_[fingertip][k][e];
  return x;
}

const char* to_string(ElementSlipState s) {
  switch (s) {
    case ElementSlipState::kNone:
      return "none";
    case ElementSlipState::kStick:
      return "stick";
    case ElementSlipState::kIncipient:
      return "incipient";
    case ElementSlipState::kSlip:
      return "slip";
  }
  return "?";
}

ArmMotion ArmMotionEstimator::update(const WristPose& wrist, double now_s) noexcept {
  const bool finite =
      is_finite(wrist.position_m) && std::isfinite(wrist.yaw_rad) && std::isfinite(now_s);
  if (!finite) return motion_ = ArmMotion{};
  if (has_last_ && now_s > last_s_) {
    const double dt = now_s - last_s_;
    const double speed = norm(wrist.position_m - last_.position_m) / dt;
    const double yaw = (wrist.yaw_rad - last_.yaw_rad) / dt;
    motion_ = ArmMotion{std::isfinite(speed) ? speed : 0.0, std::isfinite(yaw) ? yaw : 0.0};
  } else if (!has_last_) {
    motion_ = ArmMotion{};
  }
  if (!has_last_ || now_s > last_s_) {
    last_ = wrist;
    last_s_ = now_s;
    has_last_ = true;
  }
  return motion_;
}

bool paper_slip(const ElementReading& r, double threshold_mm) noexcept {
  if (!r.contact || !r.has_displacement) return false;
  if (!std::isfinite(r.fz) || !std::isfinite(r.dx_mm) || !std::isfinite(r.dy_mm)) return false;
  const double moved = std::hypot(r.dx_mm, r.dy_mm);
  return std::isfinite(moved) && moved > threshold_mm;
}

SlipDetector::SlipDetector(SlipDetectorKind kind, const Config& cfg)
    : kind_(kind),
      grip_(cfg.grip),
      field_{cfg.field_partial_slip_ratio, cfg.field_edge_ratio,    cfg.field_drop_ratio,
             cfg.field_min_fz_n,           cfg.field_arm_speed_mps, cfg.field_arm_yaw_rate_rps},
      mu_initial_(cfg.field_mu_initial) {
  reset();
}

void SlipDetector::reset() noexcept {
  for (auto& tip : history_)
    tip.fill(ElementHistory{});
  mu_.fill(mu_initial_);
  out_.fill(FingertipSlip{});
  total_fz_.fill(0.0);
  last_ts_ns_.fill(0);
  period_s_.fill(0.0);
  share_slipping_.fill(0.0);
  for (auto& tip : has_features_)
    tip.fill(false);
}

const FingertipSlip& SlipDetector::update(std::size_t f, const FingertipInput& in,
                                          double threshold_mm, const ArmMotion& arm) noexcept {
  FingertipSlip& out = out_[f];
  out = FingertipSlip{};
  if (kind_ != SlipDetectorKind::kPaper) out.mu_estimate = mu_[f];
  if (!in.fresh) return out;
  if (kind_ == SlipDetectorKind::kPaper) {
    decide_paper(in, threshold_mm, out);
  } else {
    decide_field(f, in, threshold_mm, arm, out);
  }
  for (std::size_t i = 0; i < element_count(in); ++i) {
    const ElementSlipState s = out.state[i];
    if (s == ElementSlipState::kIncipient) ++out.incipient;
    if (slipping(s)) ++out.slipping;
    if (static_cast<int>(s) > static_cast<int>(out.fingertip)) out.fingertip = s;
  }
  return out;
}

void SlipDetector::decide_paper(const FingertipInput& in, double threshold_mm,
                                FingertipSlip& out) noexcept {
  for (std::size_t i = 0; i < element_count(in); ++i) {
    const ElementReading& r = in.elements[i];
    if (!r.contact || !r.has_displacement) continue;
    if (paper_slip(r, threshold_mm)) {
      out.state[i] = ElementSlipState::kSlip;
      out.slip_mm[i] = std::hypot(r.dx_mm, r.dy_mm);
      out.reasons[i] = kSlipMoved;
    } else {
      out.state[i] = ElementSlipState::kStick;
    }
  }
}

double SlipDetector::frame_period_s(std::size_t f, std::int64_t ts) noexcept {
  if (ts > last_ts_ns_[f] && ts - last_ts_ns_[f] < 1'000'000'000 && last_ts_ns_[f] > 0)
    period_s_[f] = static_cast<double>(ts - last_ts_ns_[f]) * 1e-9;
  last_ts_ns_[f] = ts;
  return period_s_[f];
}

void SlipDetector::decide_field(std::size_t f, const FingertipInput& in, double thr,
                                const ArmMotion& arm, FingertipSlip& out) noexcept {
  const std::size_t count = element_count(in);
  auto& hist = history_[f];
  for (std::size_t i = count; i < kMaxSlipElements; ++i)
    hist[i] = ElementHistory{};

  const field::RigidFit fit = field::fit_contact(in, count, thr);
  const double rigid = field::length(fit.tx, fit.ty);
  out.rigid_mm = std::isfinite(rigid) ? rigid : 0.0;
  const field::ContactMotion contact{out.rigid_mm > thr,
                                     std::abs(arm.speed_mps) > field_.arm_speed_mps ||
                                         std::abs(arm.yaw_rate_rps) > field_.arm_yaw_rate_rps};
  const double mu = mu_[f] = field::estimate_friction(mu_[f], in, count, hist, field_.min_fz_n);
  out.mu_estimate = mu;

  const bool learn = kind_ == SlipDetectorKind::kLearned;
  SlipColumns& columns = columns_[f];
  auto& has_feats = has_features_[f];
  auto& column_of = column_of_[f];
  has_feats.fill(false);
  std::size_t n = 0;  // elements with signals: columns [0, n)
  const learned::ContactCounts counts =
      learn ? learned::count_contact(in, count, fit, thr) : learned::ContactCounts{};
  const double last_total_fz = total_fz_[f];
  if (learn) total_fz_[f] = counts.total_fz_n;
  const double period = frame_period_s(f, in.camera_timestamp_ns);
  std::uint32_t n_field_slipping = 0;
  const double inv = thr > 0 ? 1.0 / thr : 0.0;  // lengths in units of thr

  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    ElementHistory& h = hist[i];
    if (!field::usable(r)) {
      h = ElementHistory{};
      continue;
    }
    const field::ElementLoad load = field::element_load(r, field_.min_fz_n);
    if (!r.has_displacement) {
      h = ElementHistory{};
      h.valid = true;
      h.ratio = load.ratio;
      h.fz = r.fz;
      out.state[i] = ElementSlipState::kNone;
      continue;
    }
    const field::ElementMotion motion = field::element_motion(r, fit);
    const std::uint8_t why = field::reasons(field_, load, motion, r.fz, h, mu, thr, contact);
    if (learn) {
      learned::write_element_signals(
          {r, load, motion, h, fit, out.rigid_mm, mu, inv, why, h.valid && h.sliding}, n, columns);
      column_of[i] = static_cast<std::uint8_t>(n++);
      has_feats[i] = true;
      if (why != 0) ++n_field_slipping;
    }
    out.reasons[i] = why;
    if (why != 0) {
      out.state[i] = field::slip_state(contact, motion.surface, thr);
      const double v = std::max({motion.departed, motion.surface, motion.moved});
      out.slip_mm[i] = std::isfinite(v) ? v : 0.0;
    } else {
      out.state[i] = ElementSlipState::kStick;
    }
    h = ElementHistory{true,
                       why != 0,
                       load.ratio,
                       r.fz,
                       h.valid ? r.fz - h.fz : 0.0,
                       motion.moved * inv,
                       h.valid ? h.moved : 0.0,
                       motion.departed * inv};
  }
  if (!learn) return;

  // The fingertip's signals complete the columns (the share of the contact the field rules
  // decided slipping, now and in the last frame, among them); then the model decides.
  const double share =
      counts.measured > 0 ? static_cast<double>(n_field_slipping) / counts.measured : 0.0;
  const double share_prev = share_slipping_[f];
  share_slipping_[f] = share;
  learned::write_fingertip_signals(
      {out.rigid_mm, arm, counts, last_total_fz, thr, inv, mu, period, share, share_prev}, n,
      columns);
  decide_learned(f, count, thr, contact.moves, out);
}

void SlipDetector::decide_learned(std::size_t f, std::size_t count, double thr, bool contact_moves,
                                  FingertipSlip& out) noexcept {
  const ObliviousForest& forest = model(grip_);
  if (forest.trees() == 0) return;
  const SlipColumns& columns = columns_[f];
  std::size_t n = 0;
  for (std::size_t i = 0; i < count; ++i)
    n += has_features_[f][i] ? 1 : 0;
  forest.score_columns(columns, n, score_);
  const auto decision = static_cast<float>(model_decision(grip_));
  const auto& moved = columns[column(SlipSignal::kMovedDr)];
  const auto& departed = columns[column(SlipSignal::kDepartedDr)];
  const auto& surface = columns[column(SlipSignal::kSurfaceDr)];
  for (std::size_t i = 0; i < count; ++i) {
    if (!has_features_[f][i]) continue;
    const std::size_t e = column_of_[f][i];
    const bool slides = score_[e] > decision;
    const std::uint8_t why = out.reasons[i];
    out.reasons[i] = slides ? (why != 0 ? why : kSlipLearned) : 0;
    if (slides) {
      out.state[i] = contact_moves || surface[e] > 1.0f ? ElementSlipState::kSlip
                                                        : ElementSlipState::kIncipient;
      const double v = static_cast<double>(std::max({moved[e], departed[e], surface[e]})) * thr;
      out.slip_mm[i] = std::isfinite(v) ? v : 0.0;
    } else {
      out.state[i] = ElementSlipState::kStick;
      out.slip_mm[i] = 0.0;
    }
  }
}

}  // namespace tactile::control
