#include "field_rules.hpp"

#include <algorithm>

namespace tactile::control::field {
namespace {

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

RigidFit fit_contact(const FingertipInput& in, std::size_t count, double thr) {
  const auto measured = [&](std::size_t i) {
    const ElementReading& r = in.elements[i];
    return usable(r) && r.has_displacement;
  };
  RigidFit fit = fit_rigid(in, count, measured);
  if (fit.rigid()) {
    const RigidFit first = fit;
    const auto inlier = [&](std::size_t i) {
      if (!measured(i)) return false;
      const ElementReading& r = in.elements[i];
      return length(r.dx_mm - first.at_x(r.y_px), r.dy_mm - first.at_y(r.x_px)) <= thr;
    };
    const RigidFit second = fit_rigid(in, count, inlier);
    if (second.rigid()) fit = second;
  }
  return fit;
}

double estimate_friction(double mu, const FingertipInput& in, std::size_t count,
                         std::span<const ElementHistory> history, double fn_min_n) {
  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    const ElementHistory& h = history[i];
    if (!usable(r) || r.fz < fn_min_n || !h.valid) continue;
    const double ratio = std::min(length(r.fx, r.fy) / r.fz, h.ratio);
    if (std::isfinite(ratio) && ratio > mu && ratio < 10.0) mu = ratio;
  }
  return mu;
}

}  // namespace tactile::control::field
