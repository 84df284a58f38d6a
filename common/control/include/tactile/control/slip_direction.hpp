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

// The shear load along gravity one fingertip carries: the sum of F_t . gravity_axis over its
// in-contact elements with finite forces (N). Positive: the object pulls along gravity.
double load_along_gravity(const FingertipInput& in, Vec3 gravity_axis) noexcept;

}  // namespace tactile::control
