// ArmServer's per-message path allocates nothing once its buffers have grown: a command taken,
// checked and handed to the backend, and an ArmState sent back (docs/arm.md, "The backend").
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "tactile/arm/arm_server.hpp"
#include "tactile/arm/kinematic_arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile::arm {
namespace {

using namespace std::chrono_literals;

TEST(ArmServerAllocations, ACommandAndAStateAllocateNothing) {
  zmq::context_t ctx;
  KinematicArm arm({}, 0);
  ArmServerOptions o;
  o.endpoint = "tcp://127.0.0.1:*";
  ArmServer server(ctx, o, arm);
  wire::Dealer hand(ctx, server.endpoint());
  control::FingerVelocities v;
  v.velocity_mps = {Vec3{0, 0, 0.001}, Vec3{0, 0, 0.001}};
  v1::Envelope e;
  wire::Answers answers;
  answers.add({0, 5, 1000});
  answers.add({1, 5, 1000});
  std::string bytes;
  std::array<zmq::socket_ref, 1> sockets{server.socket()};
  for (int i = 1; i <= 20; ++i) {
    wire::fill_arm_command(control::Command::velocities(v), static_cast<std::uint64_t>(i), 1,
                           answers, o.fingertip_ids, *e.mutable_arm_command());
    wire::encode(e, bytes);
    ASSERT_TRUE(hand.send(wire::bytes_of(bytes)));
    ASSERT_NE(wire::poll_readable(sockets, 2000ms), 0U);
    const std::int64_t now = i * 1'000'000;
    std::size_t allocations = 0;
    {
      const testing::AllocationScope scope;
      ASSERT_TRUE(server.serve_one(now));
      ASSERT_TRUE(server.send_state(now));
      allocations = scope.count();
    }
    if (i > 3) {
      EXPECT_EQ(allocations, 0U) << "message " << i;  // after the buffers grew
    }
  }
  EXPECT_EQ(server.counters().commands, 20U);
}

}  // namespace
}  // namespace tactile::arm
