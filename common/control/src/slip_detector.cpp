#include "tactile/control/slip_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tactile::control {

namespace {

bool usable(const ElementReading& r) {
  return r.contact && std::isfinite(r.fz) && std::isfinite(r.dx_mm) && std::isfinite(r.dy_mm) &&
         std::isfinite(r.x_px) && std::isfinite(r.y_px) && std::isfinite(r.fx) &&
         std::isfinite(r.fy);
}

std::size_t element_count(const FingertipInput& in) {
  return std::min(in.elements.size(), kMaxSlipElements);
}

// The rigid motion of the contact over the frame: d(p) = t + w * perp(p - c), with p in pixels,
// d in mm (w in mm per pixel). Weighted least squares over the elements with weight 1.
struct RigidFit {
  double cx = 0, cy = 0;  // centroid of the fitted elements, px
  double tx = 0, ty = 0;  // translation, mm per frame
  double w = 0;           // rotation, mm per px per frame
  std::uint32_t n = 0;

  double at_x(double y) const { return tx - w * (y - cy); }
  double at_y(double x) const { return ty + w * (x - cx); }
};

template <typename Use>
RigidFit fit_rigid(const FingertipInput& in, std::size_t count, Use use) {
  RigidFit fit;
  double sx = 0, sy = 0, sdx = 0, sdy = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!use(i)) continue;
    const ElementReading& r = in.elements[i];
    sx += r.x_px;
    sy += r.y_px;
    sdx += r.dx_mm;
    sdy += r.dy_mm;
    ++fit.n;
  }
  if (fit.n == 0) return fit;
  const double n = fit.n;
  fit.cx = sx / n;
  fit.cy = sy / n;
  fit.tx = sdx / n;
  fit.ty = sdy / n;
  if (fit.n < 3) return fit;
  double num = 0, den = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!use(i)) continue;
    const ElementReading& r = in.elements[i];
    const double px = r.x_px - fit.cx;
    const double py = r.y_px - fit.cy;
    num += px * (r.dy_mm - fit.ty) - py * (r.dx_mm - fit.tx);
    den += px * px + py * py;
  }
  if (den > 1e-9 && std::isfinite(num / den)) fit.w = num / den;
  return fit;
}

}  // namespace

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
      rho_(cfg.field_partial_slip_ratio),
      edge_(cfg.field_edge_ratio),
      drop_(cfg.field_drop_ratio),
      mu_initial_(cfg.field_mu_initial),
      fn_min_n_(cfg.field_min_fz_n),
      arm_speed_mps_(cfg.field_arm_speed_mps),
      arm_yaw_rps_(cfg.field_arm_yaw_rate_rps) {
  reset();
}

void SlipDetector::reset() noexcept {
  for (auto& tip : history_)
    tip.fill(History{});
  mu_.fill(mu_initial_);
  out_.fill(FingertipSlip{});
}

const FingertipSlip& SlipDetector::update(std::size_t f, const FingertipInput& in,
                                          double threshold_mm, const ArmMotion& arm) noexcept {
  FingertipSlip& out = out_[f];
  out = FingertipSlip{};
  if (kind_ == SlipDetectorKind::kField) out.mu_estimate = mu_[f];
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

void SlipDetector::decide_field(std::size_t f, const FingertipInput& in, double thr,
                                const ArmMotion& arm, FingertipSlip& out) noexcept {
  const std::size_t count = element_count(in);
  auto& hist = history_[f];
  double& mu = mu_[f];
  for (std::size_t i = count; i < kMaxSlipElements; ++i)
    hist[i] = History{};

  // (a) The rigid motion of the contact: fitted to every element with a displacement, then
  // again without the elements that departed from the first fit by more than dr.
  const auto measured = [&](std::size_t i) {
    const ElementReading& r = in.elements[i];
    return usable(r) && r.has_displacement;
  };
  RigidFit fit = fit_rigid(in, count, measured);
  if (fit.n >= 3) {
    const RigidFit first = fit;
    const auto inlier = [&](std::size_t i) {
      if (!measured(i)) return false;
      const ElementReading& r = in.elements[i];
      return std::hypot(r.dx_mm - first.at_x(r.y_px), r.dy_mm - first.at_y(r.x_px)) <= thr;
    };
    const RigidFit second = fit_rigid(in, count, inlier);
    if (second.n >= 3) fit = second;
  }
  out.rigid_mm = std::isfinite(std::hypot(fit.tx, fit.ty)) ? std::hypot(fit.tx, fit.ty) : 0.0;
  const bool contact_moves = out.rigid_mm > thr;
  const bool arm_moves =
      std::abs(arm.speed_mps) > arm_speed_mps_ || std::abs(arm.yaw_rate_rps) > arm_yaw_rps_;

  // (b) The friction estimate: no element's load ratio exceeds mu. A ratio counts once it held
  // for two frames in a row (the smaller of the two), so one noisy frame does not set it.
  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    const History& h = hist[i];
    if (!usable(r) || r.fz < fn_min_n_ || !h.valid) continue;
    const double ratio = std::min(std::hypot(r.fx, r.fy) / r.fz, h.ratio);
    if (std::isfinite(ratio) && ratio > mu && ratio < 10.0) mu = ratio;
  }
  out.mu_estimate = mu;

  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    History& h = hist[i];
    if (!usable(r)) {
      h = History{};
      continue;
    }
    const double ft = std::hypot(r.fx, r.fy);
    const double ratio = r.fz >= fn_min_n_ ? ft / r.fz : 0.0;
    if (!r.has_displacement) {
      h = History{true, false, ratio};
      out.state[i] = ElementSlipState::kNone;
      continue;
    }
    const double moved = std::hypot(r.dx_mm, r.dy_mm);
    const double departed =
        fit.n >= 3 ? std::hypot(r.dx_mm - fit.at_x(r.y_px), r.dy_mm - fit.at_y(r.x_px)) : 0.0;
    const double surface = fit.n >= 3 ? std::hypot(fit.at_x(r.y_px), fit.at_y(r.x_px)) : moved;
    const bool loaded = ratio >= rho_ * mu;
    const bool at_edge = ratio >= edge_ * mu;
    const bool was = h.valid && h.sliding;
    // A breakaway: the load ratio fell from the cone's edge by more than drop * mu (a grip that
    // opens lowers F_t and F_n together: not a breakaway).
    const bool broke =
        h.valid && h.ratio >= edge_ * mu && r.fz >= fn_min_n_ && h.ratio - ratio > drop_ * mu;
    const bool moved_loaded = moved > thr && (loaded || was);
    // Only an element at the cone's edge (now or in the last frame) can leave a contact's rigid
    // motion: a release, or the slipping rim of a partial slip. Elsewhere a departure is the
    // fit's error (an opening grip, a contact of few elements).
    const bool left_rigid = departed > thr && (at_edge || h.ratio >= edge_ * mu || was);
    // (c) Still slipping: at the cone's edge while the contact or the arm moves.
    const bool dragged = was && at_edge && (contact_moves || surface > thr || arm_moves);
    const std::uint8_t why = (moved_loaded ? kSlipMoved : 0) | (left_rigid ? kSlipLeftRigid : 0) |
                             (broke ? kSlipBrokeAway : 0) | (dragged ? kSlipDragged : 0);
    out.reasons[i] = why;
    const bool slides = why != 0;
    if (slides) {
      // Gross slip where the contact itself moves over the element (translation or rotation);
      // incipient where the element alone left a contact that sticks.
      out.state[i] =
          contact_moves || surface > thr ? ElementSlipState::kSlip : ElementSlipState::kIncipient;
      const double v = std::max({departed, surface, moved});
      out.slip_mm[i] = std::isfinite(v) ? v : 0.0;
    } else {
      out.state[i] = ElementSlipState::kStick;
    }
    h = History{true, slides, ratio};
  }
}

}  // namespace tactile::control
