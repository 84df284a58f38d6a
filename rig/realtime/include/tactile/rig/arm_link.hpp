#pragma once

// The rig's side of the arm link: wire commands into world commands and the world into
// ArmState. Pure conversions.
#include <cstdint>

#include "tactile/rig/control_link.hpp"
#include "tactile/rig/world.hpp"
#include "tactile/wire/arm.hpp"

namespace tactile::rig {

// The world's arm as an ArmState.
wire::ArmStateData arm_state_of(const World& world, std::int64_t time_ns,
                                std::uint64_t last_command_sequence);

}  // namespace tactile::rig
