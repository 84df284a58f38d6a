#pragma once

// The flag analyzer (paper Fig. 5): TOUCH, SLIP and OVER from the latest readings of each
// fingertip. With the margin grip TOUCH also comes from the fingertip's total F_z above
// grip_touch_n, a light contact well under F1. SEARCH and MOVE are modes the sequencer chooses;
// they are copied into Flags here so that one struct describes the hand.
#include <array>
#include <limits>

#include "tactile/control/config.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

class FlagAnalyzer {
 public:
  explicit FlagAnalyzer(const Config& cfg)
      : f1_n_(cfg.f1_n),
        f2_n_(cfg.f2_n),
        touch_total_n_(cfg.grip == GripKind::kMargin ? cfg.grip_touch_n : kNoTotalTouch),
        dr_mm_(cfg.dr_mm),
        twist_factor_(cfg.twist_dr_factor) {}

  // The slip threshold in force: dr, or dr * twist_dr_factor in Phase II.
  double dr(bool twist_phase) const { return twist_phase ? dr_mm_ * twist_factor_ : dr_mm_; }

  // One fingertip. Readings with a non-finite value are ignored (no contact). Only an
  // in-contact reading with has_displacement on a fresh frame can slip: a frame seen again
  // must not count twice.
  FingertipFlags analyze(const FingertipInput& in, bool twist_phase) const noexcept;
  // The same with SLIP from a slip detector's decisions on this frame (SlipDetector::update).
  FingertipFlags analyze(const FingertipInput& in, const FingertipSlip& slip) const noexcept;

  // Both fingertips, with the fingers' mode.
  Flags analyze(const std::array<FingertipInput, kFingertips>& in, FingerMode mode,
                bool twist_phase) const noexcept;
  Flags analyze(const std::array<FingertipInput, kFingertips>& in, FingerMode mode,
                const std::array<const FingertipSlip*, kFingertips>& slip) const noexcept;

 private:
  // The paper's grip touches at F1 on one element only.
  static constexpr double kNoTotalTouch = std::numeric_limits<double>::infinity();

  double f1_n_;
  double f2_n_;
  double touch_total_n_;  // the margin grip's light contact: the fingertip's total F_z
  double dr_mm_;
  double twist_factor_;
};

// The unit inward normal of element `index`, or (0, 0, 1) when the input has none usable.
Vec3 element_normal(const FingertipInput& in, std::int32_t index) noexcept;

}  // namespace tactile::control
