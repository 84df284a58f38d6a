#pragma once

// Slip direction analysis (paper sections III and IV.b): among the slipping elements of both
// fingertips take the one with the largest normal force; the sign of its displacement along the
// gravity axis classifies the grasp state. Positive: the object pulls along gravity (its weight),
// a grasp. Negative: it is pushed against gravity (it met the bottle or the ground), a release.
#include <array>
#include <cstdint>

#include "tactile/control/types.hpp"

namespace tactile::control {

enum class SlipClass : std::uint8_t { kNone, kGrasp, kRelease };
const char* to_string(SlipClass c);

struct SlipDirection {
  SlipClass classification = SlipClass::kNone;
  std::int8_t fingertip = kNoFingertip;  // where the reference element is
  std::int32_t index = kNoElement;       // its position in FingertipInput::elements
  std::uint32_t element_id = 0;
  double fz_n = 0;
  double along_gravity_mm = 0;  // its per-frame displacement projected on the gravity axis
};

// `flags` must come from FlagAnalyzer::analyze on the same inputs (it names the slipping
// element with the largest F_z of each fingertip). No slip, or a displacement along gravity not
// beyond `deadband_mm` in magnitude, gives kNone.
SlipDirection analyze_slip_direction(const std::array<FingertipInput, kFingertips>& in,
                                     const Flags& flags, Vec3 gravity_axis,
                                     double deadband_mm) noexcept;

// The shear load one fingertip carries along `axis` (fingertip frame): the sum of F_t . axis over
// its in-contact elements with finite forces (N). Along gravity_axis, positive: the object pulls
// along gravity.
double shear_load_along(const FingertipInput& in, Vec3 axis) noexcept;

// The twist torque the fingertips carry (N m): the moment their shear forces apply to the object
// about the wrist's axis, +z_w (positive: counter-clockwise seen from above). x_f is horizontal
// and tangent to the object at each fingertip (types.hpp) and a reading's F is the feeler's
// deflection force, the opposite of what it applies: each fingertip adds minus its shear load
// along x_f times its distance from the axis, |x_w| of ArmFeedback::fingertip_position_m. F_y
// (vertical) and the normal forces (toward the axis) have no moment about it. 0 when a position is
// not finite.
double twist_torque_nm(const std::array<FingertipInput, kFingertips>& in,
                       const ArmFeedback& arm) noexcept;

}  // namespace tactile::control
