#include "tactile/control/finger_speed_estimator.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

#include "tactile/control/flag_analyzer.hpp"

namespace tactile::control {

namespace {
constexpr Vec3 kZero{0.0, 0.0, 0.0};
constexpr Vec3 kSqueeze{0.0, 0.0, 1.0};
constexpr double kNever = -std::numeric_limits<double>::infinity();
}  // namespace

const char* to_string(FingerAction a) {
  switch (a) {
    case FingerAction::kIdle:
      return "idle";
    case FingerAction::kApproach:
      return "approach";
    case FingerAction::kHold:
      return "hold";
    case FingerAction::kRecompress:
      return "recompress";
    case FingerAction::kBackOff:
      return "back_off";
  }
  return "?";
}

Vec3 bound_velocity(Vec3 v, double max_speed) noexcept {
  if (!is_finite(v) || !(max_speed > 0)) return kZero;
  const double speed = norm(v);
  if (!std::isfinite(speed)) return kZero;
  if (speed <= max_speed) return v;
  // Keep the direction, shorten the vector; the factor is < 1, so the result stays finite.
  return (max_speed / speed) * v;
}

FingerSpeedEstimator::FingerSpeedEstimator(const Config& cfg)
    : approach_speed_(cfg.approach_speed_mps),
      recompress_gain_(cfg.recompress_gain_mps),
      recompress_duration_(cfg.recompress_duration_s),
      recompress_limit_n_(cfg.recompress_max_f2_fraction * cfg.f2_n),
      backoff_speed_(cfg.backoff_speed_mps),
      max_speed_(cfg.max_finger_speed_mps),
      margin_(cfg.grip == GripKind::kMargin),
      grip_(cfg) {
  reset();
}

void FingerSpeedEstimator::reset() noexcept {
  stop();
  grip_.reset();
}

void FingerSpeedEstimator::stop_for_stale() noexcept {
  stop();
  grip_.pause();
}

void FingerSpeedEstimator::stop() noexcept {
  velocity_.fill(kZero);
  action_.fill(FingerAction::kIdle);
  recompress_until_.fill(kNever);
}

FingerAction FingerSpeedEstimator::margin_move(std::size_t f, const GripOutput& g, double now_s,
                                               Vec3& v) noexcept {
  v = g.squeeze_mps * kSqueeze;
  if (g.raised[f]) {
    recompress_until_[f] = now_s + recompress_duration_;
    return FingerAction::kRecompress;
  }
  const bool recompressing = action_[f] == FingerAction::kRecompress;
  return recompressing && now_s < recompress_until_[f] ? FingerAction::kRecompress
                                                       : FingerAction::kHold;
}

FingerSpeedOutput FingerSpeedEstimator::update(
    FingerMode mode, const Flags& flags, const std::array<FingertipInput, kFingertips>& inputs,
    double now_s, const GripContext& grip) noexcept {
  if (mode != mode_) {
    // The margin grip's target belongs to one grasp: a search starts another.
    if (mode != FingerMode::kMove) grip_.reset();
    // A new mode starts from rest: a new search has touched nothing yet, and a re-compression
    // does not outlive the step that started it.
    mode_ = mode;
    touched_.fill(false);
    recompress_until_.fill(kNever);
    for (FingerAction& a : action_) {
      if (a == FingerAction::kRecompress) a = FingerAction::kHold;
    }
  }

  FingerSpeedOutput out;
  GripOutput g;
  if (margin_ && mode == FingerMode::kMove) g = grip_.update(flags, inputs, grip, now_s);
  for (std::size_t f = 0; f < kFingertips; ++f) {
    const FingertipFlags& ff = flags.fingertip[f];
    const FingerAction before = action_[f];
    Vec3 v = kZero;
    FingerAction action = FingerAction::kIdle;

    if (mode == FingerMode::kOff) {
      action = FingerAction::kIdle;
    } else if (ff.over) {
      // OVER before everything: squeezing further could crush the object or the sensor.
      v = -backoff_speed_ * kSqueeze;
      action = FingerAction::kBackOff;
      touched_[f] = true;
      recompress_until_[f] = kNever;
    } else if (mode == FingerMode::kSearch) {
      touched_[f] = touched_[f] || ff.touch;
      if (touched_[f]) {
        action = FingerAction::kHold;
      } else {
        v = approach_speed_ * kSqueeze;
        action = FingerAction::kApproach;
      }
    } else if (margin_) {
      action = margin_move(f, g, now_s, v);
      out.recompress_started[f] =
          action == FingerAction::kRecompress && g.raised[f] && before != FingerAction::kRecompress;
    } else if ((ff.slip || before == FingerAction::kRecompress) &&
               ff.max_fz_n >= recompress_limit_n_) {
      // No headroom left under F2: squeezing on would only trip OVER. Hold the grip.
      action = FingerAction::kHold;
      recompress_until_[f] = kNever;
    } else if (ff.slip) {
      // Fig. 6: the element with the largest normal force gives the direction, its inward
      // normal; the re-compressive velocity adds to the current one.
      const Vec3 current = before == FingerAction::kRecompress ? velocity_[f] : kZero;
      const Vec3 n = element_normal(inputs[f], ff.max_fz_index);
      v = current + recompress_gain_ * n;  // bounded below, with every other velocity
      action = FingerAction::kRecompress;
      recompress_until_[f] = now_s + recompress_duration_;
      out.recompress_started[f] = before != FingerAction::kRecompress;
    } else if (before == FingerAction::kRecompress && now_s < recompress_until_[f]) {
      v = velocity_[f];
      action = FingerAction::kRecompress;
    } else {
      action = FingerAction::kHold;
    }

    out.over_started[f] = ff.over && !over_[f];
    over_[f] = ff.over;
    velocity_[f] = bound_velocity(v, max_speed_);
    action_[f] = action;
    out.velocity_mps[f] = velocity_[f];
    out.action[f] = action;
  }
  return out;
}

}  // namespace tactile::control
