#include "tactile/control/flag_analyzer.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace tactile::control {

namespace {

// TOUCH, OVER and the largest F_z from the readings; SLIP from `slips(i)`, the decision on
// element i of a fresh frame.
template <typename Slips>
FingertipFlags analyze_with(const FingertipInput& in, double f1_n, double f2_n,
                            double touch_total_n, Slips slips) noexcept {
  FingertipFlags f;
  double best_fz = -std::numeric_limits<double>::infinity();
  double best_slip_fz = best_fz;
  // Indices travel as int32 (kNoElement = -1); a sensor has tens of elements.
  const std::size_t count =
      std::min<std::size_t>(in.elements.size(), std::numeric_limits<std::int32_t>::max());
  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    if (!r.contact) continue;
    if (!std::isfinite(r.fz) || !std::isfinite(r.dx_mm) || !std::isfinite(r.dy_mm)) continue;
    const auto index = static_cast<std::int32_t>(i);
    if (r.fz > f1_n) f.touch = true;
    if (r.fz > f2_n) f.over = true;
    f.total_fz_n += r.fz;
    ++f.contact_elements;
    if (r.fz > best_fz) {
      best_fz = r.fz;
      f.max_fz_index = index;
    }
    if (!r.has_displacement) continue;
    const double moved = std::hypot(r.dx_mm, r.dy_mm);
    if (!std::isfinite(moved)) continue;
    if (moved > f.max_slip_mm) f.max_slip_mm = moved;
    if (in.fresh && slips(i)) {
      f.slip = true;
      if (f.slipping_elements < kMaxSlipElements) f.slipping_ids[f.slipping_elements] = r.id;
      ++f.slipping_elements;
      if (r.fz > best_slip_fz) {
        best_slip_fz = r.fz;
        f.slip_max_fz_index = index;
      }
    }
  }
  if (f.max_fz_index != kNoElement) f.max_fz_n = best_fz;
  if (!std::isfinite(f.total_fz_n)) f.total_fz_n = 0;
  // The paper's TOUCH: a slipping element touches even below F1.
  f.touch = f.touch || f.slip || f.total_fz_n > touch_total_n;
  return f;
}

}  // namespace

FingertipFlags FlagAnalyzer::analyze(const FingertipInput& in, bool twist_phase) const noexcept {
  const double threshold = dr(twist_phase);
  return analyze_with(in, f1_n_, f2_n_, touch_total_n_,
                      [&](std::size_t i) { return paper_slip(in.elements[i], threshold); });
}

FingertipFlags FlagAnalyzer::analyze(const FingertipInput& in,
                                     const FingertipSlip& slip) const noexcept {
  return analyze_with(in, f1_n_, f2_n_, touch_total_n_, [&](std::size_t i) {
    return i < kMaxSlipElements && slipping(slip.state[i]);
  });
}

namespace {

// The hand's flags from each fingertip's (`tip(f)`), with the fingers' mode.
template <typename Tip>
Flags combine(FingerMode mode, Tip tip) noexcept {
  Flags flags;
  flags.search = mode == FingerMode::kSearch;
  flags.move = mode == FingerMode::kMove;
  for (std::size_t f = 0; f < kFingertips; ++f) {
    flags.fingertip[f] = tip(f);
    flags.touch = flags.touch || flags.fingertip[f].touch;
    flags.slip = flags.slip || flags.fingertip[f].slip;
    flags.over = flags.over || flags.fingertip[f].over;
  }
  return flags;
}

}  // namespace

Flags FlagAnalyzer::analyze(const std::array<FingertipInput, kFingertips>& in, FingerMode mode,
                            bool twist_phase) const noexcept {
  return combine(mode, [&](std::size_t f) { return analyze(in[f], twist_phase); });
}

Flags FlagAnalyzer::analyze(
    const std::array<FingertipInput, kFingertips>& in, FingerMode mode,
    const std::array<const FingertipSlip*, kFingertips>& slip) const noexcept {
  return combine(mode, [&](std::size_t f) { return analyze(in[f], *slip[f]); });
}

Vec3 element_normal(const FingertipInput& in, std::int32_t index) noexcept {
  constexpr Vec3 kSqueeze{0.0, 0.0, 1.0};
  if (index < 0 || static_cast<std::size_t>(index) >= in.normals.size()) return kSqueeze;
  const Vec3 n = in.normals[static_cast<std::size_t>(index)];
  if (!is_finite(n)) return kSqueeze;
  const double length = norm(n);
  if (!std::isfinite(length) || length < 1e-6) return kSqueeze;
  return (1.0 / length) * n;
}

}  // namespace tactile::control
