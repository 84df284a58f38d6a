#include "tactile/control/grip_law.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "tactile/control/slip_direction.hpp"

namespace tactile::control {

namespace {

constexpr double kGravityMps2 = 9.81;
// A clock jump longer than this counts as this much (as the controller's own clock does).
constexpr double kMaxStepS = 1.0;
// No target beyond this (N): far past any F2 bound, it only keeps the arithmetic finite.
constexpr double kMaxTargetN = 1e3;
// The grip has reached its target within this fraction (the servo's noise and lag).
constexpr double kReachedFraction = 0.9;

double finite_or(double v, double fallback) {
  return std::isfinite(v) ? v : fallback;
}

}  // namespace

GripLaw::GripLaw(const Config& cfg) : cfg_(cfg), mu_hat_(cfg.grip_mu_initial) {
  reset();
}

void GripLaw::reset() noexcept {
  target_n_ = cfg_.grip_min_n;
  has_ref_ = false;
  ref_n_ = 0;
  peak_n_.fill(0);
  twisting_ = false;
  carried_s_ = 0;
  slip_run_ = 0;
}

void GripLaw::pause() noexcept {
  paused_ = true;
}

// The latest fresh frame of each fingertip: its tangential load, its total normal force, the
// load held over the window (the arm's vibration passes through it in a few frames); the
// weight the fingertips carry in Phase I and the largest load of the current turn in Phase II.
void GripLaw::observe(const Flags& flags, const std::array<FingertipInput, kFingertips>& inputs,
                      const GripContext& ctx, double now_s, double dt) noexcept {
  for (std::size_t f = 0; f < kFingertips; ++f) {
    if (!inputs[f].fresh) continue;
    const double load = std::hypot(shear_load_along(inputs[f], Vec3{1.0, 0.0, 0.0}),
                                   shear_load_along(inputs[f], Vec3{0.0, 1.0, 0.0}));
    const double total = flags.fingertip[f].total_fz_n;
    if (!std::isfinite(load) || !std::isfinite(total)) continue;
    load_n_[f] = load;
    total_n_[f] = total;
    contacts_[f] = flags.fingertip[f].contact_elements;
    if (load >= peak_n_[f] || now_s - peak_s_[f] > cfg_.grip_load_window_s) {
      peak_n_[f] = load;
      peak_s_[f] = now_s;
    }
    // A sliding contact's shear is no measure of its friction (its spots move): only a fresh
    // frame without SLIP bounds mu.
    const bool usable = total >= cfg_.grip_min_n && !flags.fingertip[f].slip;
    const double ratio = usable ? load / total : 0.0;
    if (ratio >= ratio_peak_ || now_s - ratio_peak_s_ > cfg_.grip_load_window_s) {
      ratio_peak_ = ratio;
      ratio_peak_s_ = now_s;
    }
  }
  grip_n_ = 0.5 * (total_n_[0] + total_n_[1]);
  const double load_sum = load_n_[0] + load_n_[1];
  if (ctx.carrying && !ctx.twist) {
    weight_n_ += std::min(1.0, dt / cfg_.grip_load_window_s) * (load_sum - weight_n_);
    if (!ctx.accelerates_soon) carried_s_ += dt;
  }
  const bool turning = ctx.twist && !ctx.accelerates_soon;
  if (turning && !twisting_) twist_load_n_ = 0;
  if (turning) twist_load_n_ = std::max({twist_load_n_, load_n_[0], load_n_[1]});
  twisting_ = turning;
}

double GripLaw::demand(const GripContext& ctx) const noexcept {
  double load = std::max(peak_n_[0], peak_n_[1]);
  if (ctx.twist && ctx.accelerates_soon) {
    // Ahead of a turn: the last turn's load, or the carry's share of the weight before the first.
    load = std::max(load, twist_load_n_ > 0 ? twist_load_n_ : 0.5 * weight_n_);
  } else if (ctx.accelerates_soon) {
    // Ahead of the arm's own acceleration: each fingertip's share of m_hat a.
    load += 0.5 * weight_n_ * cfg_.grip_ff_accel_mps2 / kGravityMps2;
  }
  const double margin = ctx.twist ? cfg_.grip_twist_margin : cfg_.grip_margin;
  // Until the lift has weighed the object, a grip that lifts what the hand is meant for: a slip
  // through the whole lift reads as an object held from below (docs/slip.md). Weighed: carried
  // grip_load_window_s past the lift's planned acceleration (the load held over that window is
  // then the weight and the vibration's peak).
  // With the loading phase the grip follows the weight as it arrives instead (lift_loads_first).
  const bool floor = ctx.lifting && !weighed() && !lift_loads_first(cfg_);
  const double least = floor ? cfg_.grip_lift_n : cfg_.grip_min_n;
  // The loading phase asks at most grip_lift_n: more would follow an anchored object's pull.
  const double most = ctx.loading ? cfg_.grip_lift_n : kMaxTargetN;  // >= least: validated
  return std::clamp(finite_or(load / mu_hat_ * (1.0 + margin), kMaxTargetN), least, most);
}

// A slip frame. The grip goes up at once, from what it is now, unless the last raise has not
// taken effect yet (the grip still short of the target: that slip was the lag, not news). Only a
// slip of a grip the friction estimate set, and reached, with no planned acceleration near, says
// mu_hat is too high: it is lowered
// to the slip's load ratio, by at most grip_mu_drop in one burst (an incipient slip, at the
// contact's rim, comes at any ratio), and it does not rise again past the middle of that drop.
void GripLaw::follow_slip(const Flags& flags, const GripContext& ctx, double now_s,
                          GripOutput& out) noexcept {
  const bool reached = grip_n_ >= kReachedFraction * target_n_;
  // Not while the arm's own acceleration changes the load faster than a grip follows (the lift's
  // first slips are the weight arriving, not a friction estimate that was too high).
  const bool estimated = reached && demand_n_ > cfg_.grip_min_n && !ctx.accelerates_soon;
  const bool burst = slipped_ && now_s - last_slip_s_ < cfg_.grip_safe_s;
  if (estimated && !burst) {
    mu_before_slip_ = mu_hat_;
    mu_ceiling_ = (1.0 - 0.5 * cfg_.grip_mu_drop) * mu_hat_;
  }
  slipped_ = true;
  last_slip_s_ = now_s;
  for (std::size_t f = 0; f < kFingertips; ++f) {
    if (!flags.fingertip[f].slip) continue;
    out.raised[f] = true;
    if (!estimated || mu_before_slip_ <= 0) continue;
    if (total_n_[f] < cfg_.grip_min_n) continue;  // no usable ratio from a light touch
    const double ratio = load_n_[f] / total_n_[f];
    if (!std::isfinite(ratio)) continue;
    const double floor = (1.0 - cfg_.grip_mu_drop) * mu_before_slip_;
    mu_hat_ = std::max(std::min(mu_hat_, ratio), floor);
  }
  // Coulomb: no contact carries more than mu_s times its normal force.
  mu_hat_ = std::clamp(std::max(mu_hat_, ratio_peak_), cfg_.grip_mu_min, cfg_.grip_mu_max);
  if (reached) {
    // A grip already past a raise of the demand did not slip for want of force (the arm's start
    // or stop shakes a firm grip too): it stops relaxing, its target held (at least the demand).
    // Not raised to the grip measured: that swings with the arm's vibration, and false slips at
    // its peaks would ratchet the target up by the swing each time.
    // A slide (slip frames in a row) is no vibration's peak: the object is going, and the grip
    // goes up from what it is, however firm.
    const double step = 1.0 + cfg_.grip_slip_step;
    const bool slide = slip_run_ >= 3 && !ctx.loading;
    const bool firm = grip_n_ > demand_n_ * step && !slide;
    const double raised =
        firm ? std::max(demand_n_, target_n_) : std::max(demand_n_, grip_n_) * step;
    target_n_ = std::min(std::max(target_n_, raised), kMaxTargetN);
    // At once: the force rate is for the relaxing and the demand's steps, not for a slip.
    ref_n_ = std::max(ref_n_, target_n_);
  }
}

// No slip: the friction is at least the ratios carried; after a safe while it is probed upward
// (the next slip says how far is too far) and the target relaxes toward the demand.
void GripLaw::settle(const GripContext& ctx, double now_s, double dt) noexcept {
  const bool safe = now_s - std::max(last_slip_s_, safe_from_s_) >= cfg_.grip_safe_s;
  // Probing only where the estimate sets the grip, and not in a turn: there a slip counts toward
  // tightness.
  if (safe && !ctx.twist && demand_n_ > cfg_.grip_min_n) {
    mu_hat_ = std::max(mu_hat_, std::min(mu_hat_ * (1.0 + cfg_.grip_mu_rise_per_s * dt),
                                         mu_ceiling_ > 0 ? mu_ceiling_ : cfg_.grip_mu_max));
  }
  mu_hat_ = std::clamp(std::max(finite_or(mu_hat_, cfg_.grip_mu_initial), ratio_peak_),
                       cfg_.grip_mu_min, cfg_.grip_mu_max);
  if (demand_n_ > target_n_) {
    target_n_ = demand_n_;
  } else if (safe) {
    target_n_ += std::min(1.0, dt / cfg_.grip_relax_s) * (demand_n_ - target_n_);
  }
}

bool GripLaw::reached() const noexcept {
  return has_ref_ && grip_n_ >= kReachedFraction * target_n_;
}

GripOutput GripLaw::update(const Flags& flags,
                           const std::array<FingertipInput, kFingertips>& inputs,
                           const GripContext& ctx, double now_s) noexcept {
  GripOutput out;
  double dt = 0;
  if (std::isfinite(now_s)) {
    if (has_now_ && !paused_) dt = std::clamp(finite_or(now_s - last_now_s_, 0.0), 0.0, kMaxStepS);
    has_now_ = true;
    last_now_s_ = now_s;
  } else {
    now_s = last_now_s_;
  }
  if (paused_) {
    paused_ = false;
    safe_from_s_ = now_s;
  }

  observe(flags, inputs, ctx, now_s, dt);
  bool fresh = false;
  for (const FingertipInput& in : inputs)
    fresh = fresh || in.fresh;
  demand_n_ = demand(ctx);
  if (fresh) slip_run_ = flags.slip ? slip_run_ + 1 : 0;
  if (fresh && flags.slip) {
    follow_slip(flags, ctx, now_s, out);
  } else {
    settle(ctx, now_s, dt);
  }

  if (!has_ref_) {
    ref_n_ = grip_n_;
    has_ref_ = true;
  }
  const double step = cfg_.grip_force_rate_nps * dt;
  ref_n_ += std::clamp(target_n_ - ref_n_, -step, step);

  // The speed holds until the next update: over a longer period it must be slower for the same
  // squeeze per period (a loop gain that does not grow with the camera's period).
  // The grip's stiffness is its elements' in contact, each feeler a spring (docs/rig.md): the
  // gain is per element, so each period closes the same part of the error however many touch
  // (with all of a firm grip's elements on the full gain the loop rang, 0.3 N peak to peak).
  const double period_s = dt > 0 ? dt : cfg_.grip_servo_gain_period_s;
  const double elements = std::max(1.0, 0.5 * static_cast<double>(contacts_[0] + contacts_[1]));
  const double gain = cfg_.grip_servo_gain_mps_per_n *
                      std::min(1.0, cfg_.grip_servo_gain_period_s / period_s) / elements;
  double v = std::clamp(gain * (ref_n_ - grip_n_), -cfg_.grip_servo_max_speed_mps,
                        cfg_.grip_servo_max_speed_mps);
  // A re-compression: short of the target within recompress_duration_s of a slip, the servo
  // squeezes at its full speed (a slipping object leaves in a few tens of milliseconds; the
  // servo's own time constant is about as long).
  // And a slip never opens the fingers: the grip over its reference then is the squeeze of the
  // re-compression arriving, and the object may still be sliding.
  if (slipped_ && now_s - last_slip_s_ <= cfg_.recompress_duration_s) {
    v = grip_n_ < ref_n_ ? cfg_.grip_servo_max_speed_mps : std::max(v, 0.0);
  }
  // F2 bounds the squeeze: no element past recompress_max_f2_fraction of it.
  const double limit_n = cfg_.recompress_max_f2_fraction * cfg_.f2_n;
  for (const FingertipFlags& ff : flags.fingertip) {
    if (ff.max_fz_n >= limit_n) v = std::min(v, 0.0);
  }
  out.squeeze_mps = finite_or(v, 0.0);
  return out;
}

}  // namespace tactile::control
