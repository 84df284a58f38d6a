#include "tactile/control/twist_torque.hpp"

#include <algorithm>
#include <cmath>

namespace tactile::control {

void TwistTorquePlateau::start(double t) noexcept {
  start_s_ = t;
  last_s_ = t;
  has_level_ = false;
  level_nm_ = 0;
  building_ = false;
  peak_nm_ = 0;
  peak_s_ = t;
  latest_nm_ = 0;
}

// "Clearly above the free-turn level": by tight_torque_rise_nm, and by tight_torque_rise_ratio of
// the level itself when that is more (a thread with a larger free-turn torque varies more).
double TwistTorquePlateau::rise_nm() const noexcept {
  return std::max(cfg_.tight_torque_rise_nm, cfg_.tight_torque_rise_ratio * level_nm_);
}

bool TwistTorquePlateau::update(double torque_nm, bool fresh, bool wrist_stopped,
                                double t) noexcept {
  if (fresh && std::isfinite(torque_nm)) {
    if (!has_level_) {
      has_level_ = true;
      level_nm_ = torque_nm;
      last_s_ = t;
    }
    // The level needs a few of its time constants to settle on the free-turn torque before a
    // rise above it means anything.
    const bool judged = t - start_s_ >= 3.0 * cfg_.tight_level_s;
    if (!building_) {
      if (judged && torque_nm > level_nm_ + rise_nm()) {
        building_ = true;
        peak_nm_ = torque_nm;
        peak_s_ = t;
      } else {
        const double dt = std::max(t - last_s_, 0.0);
        level_nm_ += std::min(1.0, dt / cfg_.tight_level_s) * (torque_nm - level_nm_);
      }
    } else if (torque_nm > peak_nm_ + cfg_.tight_plateau_fraction * (peak_nm_ - level_nm_)) {
      peak_nm_ = torque_nm;
      peak_s_ = t;
    }
    last_s_ = t;
    latest_nm_ = torque_nm;
  }
  // Still built: a passing bump that fell back to the level is no stop.
  const bool built = building_ && latest_nm_ > level_nm_ + rise_nm();
  return built && (wrist_stopped || t - peak_s_ >= cfg_.tight_plateau_s);
}

}  // namespace tactile::control
