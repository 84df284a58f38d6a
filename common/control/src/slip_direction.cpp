#include "tactile/control/slip_direction.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

namespace tactile::control {

const char* to_string(SlipClass c) {
  switch (c) {
    case SlipClass::kNone:
      return "none";
    case SlipClass::kGrasp:
      return "grasp";
    case SlipClass::kRelease:
      return "release";
  }
  return "?";
}

SlipDirection analyze_slip_direction(const std::array<FingertipInput, kFingertips>& in,
                                     const Flags& flags, Vec3 gravity_axis,
                                     double deadband_mm) noexcept {
  SlipDirection d;
  double best_fz = -std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < kFingertips; ++f) {
    const FingertipFlags& ff = flags.fingertip[f];
    if (!ff.slip || ff.slip_max_fz_index == kNoElement) continue;
    const auto i = static_cast<std::size_t>(ff.slip_max_fz_index);
    if (i >= in[f].elements.size()) continue;
    const ElementReading& r = in[f].elements[i];
    // The element with the largest normal force is the centre the object turns about when it
    // meets the ground (paper IV.b): its displacement gives the direction.
    if (r.fz > best_fz) {
      best_fz = r.fz;
      d.fingertip = static_cast<std::int8_t>(f);
      d.index = ff.slip_max_fz_index;
      d.element_id = r.id;
      d.fz_n = r.fz;
      d.along_gravity_mm = gravity_axis.x * r.dx_mm + gravity_axis.y * r.dy_mm;
    }
  }
  if (d.fingertip == kNoFingertip || !std::isfinite(d.along_gravity_mm)) return SlipDirection{};
  if (d.along_gravity_mm > deadband_mm) {
    d.classification = SlipClass::kGrasp;
  } else if (d.along_gravity_mm < -deadband_mm) {
    d.classification = SlipClass::kRelease;
  }
  return d;
}

double shear_load_along(const FingertipInput& in, Vec3 axis) noexcept {
  double load = 0;
  for (const ElementReading& r : in.elements) {
    if (!r.contact || !std::isfinite(r.fx) || !std::isfinite(r.fy)) continue;
    const double along = axis.x * r.fx + axis.y * r.fy;
    if (std::isfinite(along)) load += along;
  }
  return std::isfinite(load) ? load : 0.0;
}

double twist_torque_nm(const std::array<FingertipInput, kFingertips>& in,
                       const ArmFeedback& arm) noexcept {
  // x_f is -y_w on the left fingertip (at -x_w) and +y_w on the right one (at +x_w): on both the
  // moment about +z_w of a force F along x_f is |x_w| F, and the object receives -F.
  double torque = 0;
  for (std::size_t f = 0; f < kFingertips; ++f) {
    const double lever_m = std::abs(arm.fingertip_position_m[f].x);
    if (!std::isfinite(lever_m)) return 0.0;
    torque -= lever_m * shear_load_along(in[f], Vec3{1.0, 0.0, 0.0});
  }
  return std::isfinite(torque) ? torque : 0.0;
}

}  // namespace tactile::control
