// The kinematic arm follows every command exactly (docs/arm.md): straight lines at the commanded
// speed, finger velocities in the fingertip frames, an open of exactly its distance, hold, stop.
#include "tactile/arm/kinematic_arm.hpp"

#include <gtest/gtest.h>

namespace tactile::arm {
namespace {

constexpr std::int64_t kMs = 1'000'000;

wire::ReceivedCommand received(const control::Command& c) {
  wire::ReceivedCommand r;
  r.command = c;
  return r;
}

control::Command move_to(Vec3 target, double yaw, double speed, std::uint32_t id) {
  control::MoveTo m;
  m.segment_id = id;
  m.name = "MOVE1";
  m.target = {target, yaw};
  m.max_speed_mps = speed;
  m.max_yaw_rate_rps = 1.0;
  return control::Command::move(m);
}

TEST(KinematicArm, MoveToGoesInAStraightLineAtItsSpeedAndIsDoneThere) {
  KinematicArmOptions o;
  o.start = {{0, 0, 0.2}, 0};
  KinematicArm arm(o, 0);
  ASSERT_TRUE(arm.write(received(move_to({0.3, 0.4, 0.2}, 0.5, 0.1, 3)), 0));
  const wire::ArmStateData half = arm.read(2500 * kMs);  // 0.25 m of 0.5 m
  EXPECT_NEAR(half.wrist.position_m.x, 0.15, 1e-9);
  EXPECT_NEAR(half.wrist.position_m.y, 0.20, 1e-9);
  EXPECT_DOUBLE_EQ(half.wrist.yaw_rad, 0.5);  // 1 rad/s: turned long ago
  EXPECT_FALSE(half.segment_done);
  EXPECT_EQ(half.active_segment_id, 3U);
  const wire::ArmStateData done = arm.read(5001 * kMs);
  EXPECT_DOUBLE_EQ(done.wrist.position_m.x, 0.3);
  EXPECT_DOUBLE_EQ(done.wrist.position_m.y, 0.4);
  EXPECT_TRUE(done.segment_done);
}

TEST(KinematicArm, FingersFollowTheirVelocitiesAndOpenExactlyTheirDistance) {
  KinematicArmOptions o;
  o.finger_open_m = 0.03;
  KinematicArm arm(o, 0);
  control::FingerVelocities v;
  v.velocity_mps = {Vec3{0, 0, 0.01}, Vec3{0, 0, 0.005}};  // both squeeze (+z_f)
  ASSERT_TRUE(arm.write(received(control::Command::velocities(v)), 0));
  const wire::ArmStateData s = arm.read(1000 * kMs);
  EXPECT_NEAR(s.fingertip_position_m[0].x, -0.02, 1e-12);  // left moves toward +x
  EXPECT_NEAR(s.fingertip_position_m[1].x, 0.025, 1e-12);  // right toward -x
  EXPECT_DOUBLE_EQ(s.fingertip_velocity_mps[0].z, 0.01);
  ASSERT_TRUE(arm.write(received(control::Command::open_fingers({0.004, 0.002})), 1000 * kMs));
  const wire::ArmStateData opened = arm.read(3000 * kMs);  // long after the open's 0.5 s
  EXPECT_NEAR(opened.fingertip_position_m[0].x, -0.022, 1e-12);
  EXPECT_NEAR(opened.fingertip_position_m[1].x, 0.027, 1e-12);
  EXPECT_DOUBLE_EQ(opened.fingertip_velocity_mps[0].z, 0.0);
}

TEST(KinematicArm, HoldStopsWhereItIsAndStopNeedsANewSegment) {
  KinematicArmOptions o;
  o.start = {{0, 0, 0.2}, 0};
  KinematicArm arm(o, 0);
  ASSERT_TRUE(arm.write(received(move_to({1, 0, 0.2}, 0, 0.1, 1)), 0));
  arm.hold(1000 * kMs);
  const wire::ArmStateData held = arm.read(5000 * kMs);
  EXPECT_NEAR(held.wrist.position_m.x, 0.1, 1e-12);
  EXPECT_TRUE(held.holding);
  ASSERT_TRUE(arm.write(received(control::Command::stop()), 5000 * kMs));
  control::FingerVelocities v;
  v.velocity_mps = {Vec3{0, 0, 0.01}, Vec3{0, 0, 0.01}};
  EXPECT_FALSE(arm.write(received(control::Command::velocities(v)), 5000 * kMs));
  ASSERT_TRUE(arm.write(received(move_to({0.1, 0, 0.3}, 0, 0.1, 2)), 5000 * kMs));
  EXPECT_FALSE(arm.read(5500 * kMs).holding);
  EXPECT_TRUE(arm.read(6001 * kMs).segment_done);
}

TEST(KinematicArm, FingersStopAtTheEndsOfTheirStroke) {
  KinematicArmOptions o;
  o.finger_open_m = 0.01;
  KinematicArm arm(o, 0);
  control::FingerVelocities v;
  v.velocity_mps = {Vec3{0, 0, 0.01}, Vec3{0, 0, -0.1}};
  ASSERT_TRUE(arm.write(received(control::Command::velocities(v)), 0));
  const wire::ArmStateData s = arm.read(2000 * kMs);
  EXPECT_DOUBLE_EQ(s.fingertip_position_m[0].x, 0.0);
  EXPECT_DOUBLE_EQ(s.fingertip_position_m[1].x, o.finger_max_m);
  EXPECT_TRUE(s.limit);
  EXPECT_THROW(KinematicArm({{}, 0.1, 0.0, 0.06}, 0), std::invalid_argument);
}

}  // namespace
}  // namespace tactile::arm
