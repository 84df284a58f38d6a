#pragma once

// The field detector's parts (docs/slip.md, "The field detector"): the contact's rigid motion,
// each element's load and motion against it, the friction estimate, and the rules that call an
// element slipping. The field and learned detectors both run them (SlipDetector); pure and
// allocation-free.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "tactile/control/slip_detector.hpp"

namespace tactile::control::field {

// In contact with every value finite: the only readings the field detector uses.
inline bool usable(const ElementReading& r) {
  return r.contact && std::isfinite(r.fz) && std::isfinite(r.dx_mm) && std::isfinite(r.dy_mm) &&
         std::isfinite(r.x_px) && std::isfinite(r.y_px) && std::isfinite(r.fx) &&
         std::isfinite(r.fy);
}

// |(x, y)| without hypot's care for overflow and rounding (hypot costs most of the field
// detector's time); a result that overflows is infinite, and every output is checked finite.
inline double length(double x, double y) {
  return std::sqrt(x * x + y * y);
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
  // A rotation is fitted only to three elements or more; with fewer, no motion is told apart.
  bool rigid() const { return n >= 3; }
};

// Fitted to the first `count` elements with a displacement, then again without those that
// departed from the first fit by more than `threshold_mm` (when three or more remain).
RigidFit fit_contact(const FingertipInput& in, std::size_t count, double threshold_mm);

// An element's friction-cone load: |F_t| and |F_t| / F_n (0 below `fn_min_n`).
struct ElementLoad {
  double ft = 0;
  double ratio = 0;
};
inline ElementLoad element_load(const ElementReading& r, double fn_min_n) {
  const double ft = length(r.fx, r.fy);
  return {ft, r.fz >= fn_min_n ? ft / r.fz : 0.0};
}

// An element's motion over the frame (mm): its own, its departure from the contact's rigid
// motion, and the rigid motion at the element (the surface's motion over it; its own without a
// rigid fit).
struct ElementMotion {
  double moved = 0;
  double departed = 0;
  double surface = 0;
};
inline ElementMotion element_motion(const ElementReading& r, const RigidFit& fit) {
  ElementMotion m;
  m.moved = length(r.dx_mm, r.dy_mm);
  m.departed = fit.rigid() ? length(r.dx_mm - fit.at_x(r.y_px), r.dy_mm - fit.at_y(r.x_px)) : 0.0;
  m.surface = fit.rigid() ? length(fit.at_x(r.y_px), fit.at_y(r.x_px)) : m.moved;
  return m;
}

// The friction coefficient after this frame: no element's load ratio exceeds it. A ratio counts
// once it held for two frames in a row (the smaller of the two), so one noisy frame does not set
// it; ratios of 10 and above are not friction.
double estimate_friction(double mu, const FingertipInput& in, std::size_t count,
                         std::span<const ElementHistory> history, double fn_min_n);

// What the whole contact does this frame.
struct ContactMotion {
  bool moves = false;      // its rigid translation exceeds the threshold
  bool arm_moves = false;  // the arm's reported motion exceeds the field's bounds
};

// Why the element slips by the field rules (kSlip* bits; 0: it sticks), from its load and motion
// this frame, its history, the friction estimate `mu` and the threshold.
inline std::uint8_t reasons(const FieldParams& p, const ElementLoad& load, const ElementMotion& m,
                            double fz, const ElementHistory& h, double mu, double thr,
                            const ContactMotion& contact) {
  const bool loaded = load.ratio >= p.partial_slip_ratio * mu;
  const bool at_edge = load.ratio >= p.edge_ratio * mu;
  const bool was = h.valid && h.sliding;
  // A breakaway: the load ratio fell from the cone's edge by more than drop * mu (a grip that
  // opens lowers F_t and F_n together: not a breakaway).
  const bool broke = h.valid && h.ratio >= p.edge_ratio * mu && fz >= p.min_fz_n &&
                     h.ratio - load.ratio > p.drop_ratio * mu;
  const bool moved_loaded = m.moved > thr && (loaded || was);
  // Only an element at the cone's edge (now or in the last frame) can leave a contact's rigid
  // motion: a release, or the slipping rim of a partial slip. Elsewhere a departure is the fit's
  // error (an opening grip, a contact of few elements).
  const bool left_rigid = m.departed > thr && (at_edge || h.ratio >= p.edge_ratio * mu || was);
  // Still slipping: at the cone's edge while the contact or the arm moves.
  const bool dragged = was && at_edge && (contact.moves || m.surface > thr || contact.arm_moves);
  return static_cast<std::uint8_t>((moved_loaded ? kSlipMoved : 0) |
                                   (left_rigid ? kSlipLeftRigid : 0) |
                                   (broke ? kSlipBrokeAway : 0) | (dragged ? kSlipDragged : 0));
}

// A slipping element's state: gross slip where the contact itself moves over the element
// (translation or rotation), incipient where the element alone left a contact that sticks.
inline ElementSlipState slip_state(const ContactMotion& contact, double surface_mm,
                                   double threshold_mm) {
  return contact.moves || surface_mm > threshold_mm ? ElementSlipState::kSlip
                                                    : ElementSlipState::kIncipient;
}

}  // namespace tactile::control::field
