#pragma once

// The arm behind arm_bridge. THIS IS WHERE A LAB'S ARM GOES (docs/arm.md, "Connecting your arm"):
// write a class implementing arm::ArmBackend (read the arm's state, write a command, hold) for
// your arm's driver, and return it from make_backend in backend.cpp instead of the kinematic arm.
// Everything else (the socket, CURVE, the deadman, refusals, ArmStates) is arm::ArmServer's.
#include <cstdint>
#include <memory>

#include "tactile/arm/arm_server.hpp"
#include "tactile/arm/kinematic_arm.hpp"

namespace tactile::arm_bridge {

// What arm_bridge's options say about the arm itself (not the link).
struct BackendOptions {
  arm::KinematicArmOptions kinematic;
};

// Called once at start-up; throw std::runtime_error (exit status 1, one line) when the arm
// cannot be reached or configured.
std::unique_ptr<arm::ArmBackend> make_backend(const BackendOptions& options, std::int64_t now_ns);

}  // namespace tactile::arm_bridge
