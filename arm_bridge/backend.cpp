#include "backend.hpp"

namespace tactile::arm_bridge {

std::unique_ptr<arm::ArmBackend> make_backend(const BackendOptions& options, std::int64_t now_ns) {
  // ----- A LAB'S ARM GOES HERE ----------------------------------------------------------------
  // Replace the kinematic arm (no physics: it follows every command exactly) with your own
  // arm::ArmBackend, e.g.
  //   return std::make_unique<MyArm>(options, now_ns);  // connects to the arm's driver
  // Its read() reports the arm, write() starts following a command, hold() stops it now; none
  // of them may block for long: the server's loop answers hand_node and keeps the deadman.
  // ---------------------------------------------------------------------------------------------
  return std::make_unique<arm::KinematicArm>(options.kinematic, now_ns);
}

}  // namespace tactile::arm_bridge
