#include "tactile/control/grasp_search.hpp"

#include <algorithm>

namespace tactile::control {

void GraspSearch::start(double t) noexcept {
  stage_ = Stage::kSearch;
  since_s_ = t;
  touched_.fill(false);
}

bool GraspSearch::all_touched() const {
  return std::all_of(touched_.begin(), touched_.end(), [](bool touched) { return touched; });
}

GraspProgress GraspSearch::update(const Flags& flags, double t, bool grip_ready) noexcept {
  GraspProgress p;
  if (stage_ == Stage::kSearch) {
    for (std::size_t f = 0; f < kFingertips; ++f) {
      touched_[f] = touched_[f] || flags.fingertip[f].touch;
    }
    if (all_touched()) {
      p.touch = true;
      stage_ = Stage::kSettle;
      since_s_ = t;
    } else if (t - since_s_ > search_timeout_s_) {
      p.timed_out = true;
      stage_ = Stage::kIdle;
      return p;
    }
  }
  if (stage_ == Stage::kSettle && t - since_s_ >= settle_s_ &&
      (grip_ready || t - since_s_ >= settle_s_ + reach_timeout_s_)) {
    p.settled = true;
    stage_ = Stage::kIdle;
  }
  return p;
}

FingerMode GraspSearch::finger_mode() const {
  switch (stage_) {
    case Stage::kSearch:
      return FingerMode::kSearch;
    case Stage::kSettle:
      return FingerMode::kMove;
    case Stage::kIdle:
      break;
  }
  return FingerMode::kOff;
}

double grasp_force(const Flags& flags) noexcept {
  const auto weaker = std::min_element(
      flags.fingertip.begin(), flags.fingertip.end(),
      [](const FingertipFlags& a, const FingertipFlags& b) { return a.max_fz_n < b.max_fz_n; });
  return weaker->max_fz_n;
}

}  // namespace tactile::control
