#pragma once

// An arm without physics, for bringing hand_node up against a new arm before the real backend
// exists (arm_bridge, docs/arm.md): it follows every command exactly and reports where it is.
// MoveTo: the wrist goes in a straight line at max_speed_mps and turns at max_yaw_rate_rps to
// the target, no acceleration; FingerVelocities: each fingertip moves at its velocity (fingertip
// frame, docs/protocol.md "Frames of reference") until told otherwise, within its stroke; Open:
// both fingertips move along -z_f at speed_mps for distance_m; Hold: everything stops where it
// is; Stop: the same, and only a new MoveTo moves it again. Pure: time is an argument.
#include <array>
#include <cstdint>

#include "tactile/arm/arm_server.hpp"
#include "tactile/control/types.hpp"

namespace tactile::arm {

struct KinematicArmOptions {
  control::WristPose start{{0.35, -0.10, 0.25}, 0.0};
  // Each fingertip's distance from the grasp centre along the closing axis (wrist x) at the
  // start, and the stroke it stays within (LIMIT while pressed against an end).
  double finger_open_m = 0.03;
  double finger_min_m = 0.0;
  double finger_max_m = 0.06;
};

class KinematicArm final : public ArmBackend {
 public:
  // Throws std::invalid_argument for a stroke that is not 0 <= min <= open <= max, finite.
  KinematicArm(const KinematicArmOptions& options, std::int64_t start_ns);

  wire::ArmStateData read(std::int64_t now_ns) override;
  bool write(const wire::ReceivedCommand& command, std::int64_t now_ns) override;
  void hold(std::int64_t now_ns) override;

  // Moves everything to `now_ns` (read, write and hold do it first). Earlier instants are
  // ignored: the arm never goes back in time.
  void advance_to(std::int64_t now_ns);
  const wire::ArmStateData& state() const { return state_; }

 private:
  void stop_motion();

  KinematicArmOptions options_;
  std::int64_t now_ns_;
  wire::ArmStateData state_;
  control::MoveTo move_;
  bool moving_ = false;
  bool stopped_ = false;
  std::array<Vec3, control::kFingertips> finger_velocity_f_{};  // commanded, fingertip frame
  std::array<double, control::kFingertips> open_left_m_{};      // Open: distance still to go
  bool opening_ = false;
};

}  // namespace tactile::arm
