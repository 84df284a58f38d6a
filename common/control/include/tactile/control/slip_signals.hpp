#pragma once

// The learned slip detector's signals (docs/slip.md, "The learned combiner"), by name: each is one
// column of SlipColumns and one feature index of the model (slip_model.inc's kSlipModelFeature),
// in this order. Lengths are in units of the frame's threshold dr, loads in units of the friction
// estimate. The order is the model's: a signal added goes at the end, and the model is trained
// again (slip_train).
#include <array>
#include <cstddef>
#include <cstdint>

#include "tactile/control/types.hpp"  // kMaxSlipElements

namespace tactile::control {

enum class SlipSignal : std::uint8_t {
  // The element's own, this frame and the last ones.
  kMovedDr,         // |(dx, dy)|
  kDepartedDr,      // its departure from the contact's rigid motion
  kSurfaceDr,       // the rigid motion at the element (the surface's motion over it)
  kLoad,            // |F_t| / F_n over the friction estimate
  kLoadPrev,        // the same in the last frame
  kFzN,             // F_n
  kDfzN,            // F_n's change since the last frame
  kMovedPrevDr,     // kMovedDr in the last frame
  kDepartedPrevDr,  // kDepartedDr in the last frame
  // The fingertip's (the same for every element of a frame).
  kRigidDr,  // the contact's rigid translation
  // The element's own.
  kRotationDr,  // the rigid rotation's motion at the element
  // The fingertip's.
  kArmSpeedMmps,   // the arm's reported speed
  kArmYawDps,      // the arm's reported yaw rate
  kShareMoved,     // the share of the measured elements that moved more than dr
  kShareDeparted,  // the share that departed from the rigid motion by more than dr
  kTotalFzN,       // the contact's total F_n
  kTotalDfzRel,    // its relative change since the last frame
  // The element's own.
  kFieldReasons,  // the field rules' reasons (kSlip* bits)
  kFieldWas,      // the field rules decided it slipping in the last frame
  // The fingertip's.
  kMeasured,  // elements with a displacement
  kDrUm,      // the threshold dr itself, um
  kMu,        // the friction estimate
  // The element's own.
  kFtN,           // |F_t|
  kAlign,         // the cosine between its motion and the rigid translation
  kMovedPrev2Dr,  // kMovedDr two frames ago
  kDfzPrevN,      // kDfzN in the last frame
  // The fingertip's.
  kArmDr,              // the arm's motion over one frame period
  kFps,                // the frame rate from the camera's timestamps
  kShareSlipping,      // the share of the measured elements the field rules decided slipping
  kShareSlippingPrev,  // the same in the last frame
  kCount
};

inline constexpr std::size_t kSlipFeatures = static_cast<std::size_t>(SlipSignal::kCount);
// The column (and model feature index) of a signal.
constexpr std::size_t column(SlipSignal s) {
  return static_cast<std::size_t>(s);
}
// The signal's name in training files and docs ("moved_dr", ...).
const char* to_string(SlipSignal s);
// The names by column, for the trainer's files.
extern const std::array<const char*, kSlipFeatures> kSlipFeatureNames;

// One element's signals, by column.
using SlipFeatures = std::array<float, kSlipFeatures>;
// The signals of up to kMaxSlipElements elements by column (signal k of element e at [k][e]).
using SlipColumns = std::array<std::array<float, kMaxSlipElements>, kSlipFeatures>;

}  // namespace tactile::control
