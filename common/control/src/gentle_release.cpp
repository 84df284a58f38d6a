#include "tactile/control/gentle_release.hpp"

#include <algorithm>

namespace tactile::control {

Command GentleRelease::hold() noexcept {
  stage_ = Stage::kHolding;
  return Command::hold();
}

Command GentleRelease::open(double t) noexcept {
  stage_ = Stage::kOpening;
  opened_s_ = t;
  return Command::open_fingers({speed_mps_, distance_m_});
}

bool GentleRelease::update(double t, Command& command) noexcept {
  switch (stage_) {
    case Stage::kHolding:
      command = open(t);
      return false;
    case Stage::kOpening:
      if (t - opened_s_ >= distance_m_ / speed_mps_ + settle_s_) {
        stage_ = Stage::kIdle;
        return true;
      }
      return false;
    case Stage::kIdle:
      break;
  }
  return false;
}

Command GentleRelease::resume(double t) const noexcept {
  if (stage_ != Stage::kOpening) return Command::none();
  const double left = distance_m_ - speed_mps_ * std::max(t - opened_s_, 0.0);
  if (!(left > 0)) return Command::none();
  return Command::open_fingers({speed_mps_, left});
}

}  // namespace tactile::control
