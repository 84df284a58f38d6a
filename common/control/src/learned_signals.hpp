#pragma once

// The learned detector's signals (slip_signals.hpp) of one fresh frame, written by column: each
// element's own as the field rules decide it, the fingertip's once the frame is decided. Pure and
// allocation-free; a signal that is not finite is written as 0.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>

#include "field_rules.hpp"
#include "tactile/control/slip_signals.hpp"

namespace tactile::control::learned {

// A learned detector's signal: in float, 0 where it is not finite.
inline float finite_signal(double v) {
  const auto x = static_cast<float>(v);
  return std::isfinite(x) ? x : 0.0f;
}

// The signals that are each element's own, and those that are the fingertip's (the same for
// every element of a frame, written once per frame): each signal in exactly one of them, in the
// order their writers list the values.
constexpr std::array kElementSignals{
    SlipSignal::kMovedDr,    SlipSignal::kDepartedDr,   SlipSignal::kSurfaceDr,
    SlipSignal::kLoad,       SlipSignal::kLoadPrev,     SlipSignal::kFzN,
    SlipSignal::kDfzN,       SlipSignal::kMovedPrevDr,  SlipSignal::kDepartedPrevDr,
    SlipSignal::kRotationDr, SlipSignal::kFieldReasons, SlipSignal::kFieldWas,
    SlipSignal::kFtN,        SlipSignal::kAlign,        SlipSignal::kMovedPrev2Dr,
    SlipSignal::kDfzPrevN};
constexpr std::array kFingertipSignals{SlipSignal::kRigidDr,       SlipSignal::kArmSpeedMmps,
                                       SlipSignal::kArmYawDps,     SlipSignal::kShareMoved,
                                       SlipSignal::kShareDeparted, SlipSignal::kTotalFzN,
                                       SlipSignal::kTotalDfzRel,   SlipSignal::kMeasured,
                                       SlipSignal::kDrUm,          SlipSignal::kMu,
                                       SlipSignal::kArmDr,         SlipSignal::kFps,
                                       SlipSignal::kShareSlipping, SlipSignal::kShareSlippingPrev};

constexpr bool each_signal_once() {
  std::array<int, kSlipFeatures> seen{};
  for (SlipSignal s : kElementSignals)
    ++seen[column(s)];
  for (SlipSignal s : kFingertipSignals)
    ++seen[column(s)];
  for (int times : seen)
    if (times != 1) return false;
  return true;
}
static_assert(each_signal_once(), "every signal is the element's or the fingertip's, once");

// What the whole contact shows this frame: its elements with a displacement, of which those that
// moved and those that departed from the rigid fit by more than the threshold, and its total F_n.
struct ContactCounts {
  std::uint32_t measured = 0;
  std::uint32_t moved = 0;
  std::uint32_t departed = 0;
  double total_fz_n = 0;
};
ContactCounts count_contact(const FingertipInput& in, std::size_t count, const field::RigidFit& fit,
                            double threshold_mm);

// Element `e`'s own signals (column e). `inv_threshold`: 1 / dr (0 when dr is 0); `why`: the field
// rules' reasons this frame; `was`: the field rules decided it slipping in the last frame.
struct ElementSignals {
  const ElementReading& reading;
  const field::ElementLoad& load;
  const field::ElementMotion& motion;
  const ElementHistory& history;
  const field::RigidFit& fit;
  double rigid_mm = 0;
  double mu = 0;
  double inv_threshold = 0;
  std::uint8_t why = 0;
  bool was = false;
};
inline void write_element_signals(const ElementSignals& s, std::size_t e, SlipColumns& columns) {
  const ElementReading& r = s.reading;
  const ElementHistory& h = s.history;
  const field::RigidFit& fit = s.fit;
  const double inv = s.inv_threshold;
  const double moved = s.motion.moved;
  const double rx = r.x_px - fit.cx, ry = r.y_px - fit.cy;
  const double align = moved > 0 && s.rigid_mm > 0
                           ? (r.dx_mm * fit.tx + r.dy_mm * fit.ty) / (moved * s.rigid_mm)
                           : 0.0;
  const double m = s.mu > 0 ? 1.0 / s.mu : 0.0;
  const double values[] = {
      moved * inv,                                                               // moved_dr
      s.motion.departed * inv,                                                   // departed_dr
      s.motion.surface * inv,                                                    // surface_dr
      s.load.ratio * m,                                                          // load
      h.valid ? h.ratio * m : 0.0,                                               // load_prev
      r.fz,                                                                      // fz_n
      h.valid ? r.fz - h.fz : 0.0,                                               // dfz_n
      h.valid ? h.moved : 0.0,                                                   // moved_prev_dr
      h.valid ? h.departed : 0.0,                                                // departed_prev_dr
      fit.rigid() ? std::abs(fit.w) * std::sqrt(rx * rx + ry * ry) * inv : 0.0,  // rotation_dr
      static_cast<double>(s.why),                                                // field_reasons
      s.was ? 1.0 : 0.0,                                                         // field_was
      s.load.ft,                                                                 // ft_n
      align,                                                                     // align
      h.valid ? h.moved2 : 0.0,                                                  // moved_prev2_dr
      h.valid ? h.dfz : 0.0,                                                     // dfz_prev_n
  };
  static_assert(std::size(values) == kElementSignals.size());
  for (std::size_t j = 0; j < kElementSignals.size(); ++j)
    columns[column(kElementSignals[j])][e] = finite_signal(values[j]);
}

// The fingertip's signals, the same for the frame's first `n` columns.
struct FingertipSignals {
  double rigid_mm = 0;
  ArmMotion arm;
  ContactCounts counts;
  double last_total_fz_n = 0;
  double threshold_mm = 0;
  double inv_threshold = 0;
  double mu = 0;
  double period_s = 0;  // the frame period from the camera's timestamps (0: not known yet)
  double share_slipping = 0;
  double share_slipping_prev = 0;
};
void write_fingertip_signals(const FingertipSignals& s, std::size_t n, SlipColumns& columns);

}  // namespace tactile::control::learned
