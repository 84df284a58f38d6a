#pragma once

// The rig's side of the arm link (docs/system.md, "The rig in real time"): the world's arm as an
// ArmState. Who the arm answers and its deadman are arm::ArmServer's (common/arm); the world is
// its backend. Pure: time is an argument, nothing here reads a clock or touches a socket.
#include <cstdint>

#include "tactile/rig/world.hpp"
#include "tactile/wire/arm.hpp"

namespace tactile::rig {

// The world's arm as an ArmState.
wire::ArmStateData arm_state_of(const World& world, std::int64_t time_ns,
                                std::uint64_t last_command_sequence);

}  // namespace tactile::rig
