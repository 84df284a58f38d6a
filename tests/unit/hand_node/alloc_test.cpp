// hand_node's pure pieces on its per-message path allocate nothing (docs/architecture.md,
// rule 4): the arm link told of commands, heartbeats and ArmStates (with the resends after a
// deadman hold) and asked what is due, the task's start, the freshness of tactile data.
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "arm_link.hpp"
#include "tactile_freshness.hpp"
#include "task_start.hpp"

namespace tactile::hand {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(HandNodeAllocations, TheArmLinkTheStartAndTheFreshnessAllocateNothing) {
  ArmLink link({10 * kMs, 100 * kMs, 500 * kMs});
  TaskStart start(20, 5000 * kMs);
  TactileFreshness freshness(30 * kMs);
  control::MoveTo m;
  m.segment_id = 4;
  control::FingerVelocities v;
  v.velocity_mps[0].z = 0.001;
  std::size_t resent = 0;
  std::size_t allocations = 0;
  {
    const testing::AllocationScope scope;
    for (std::int64_t t = 0; t < 1000; ++t) {
      const std::int64_t now = t * kMs;
      const auto tip = static_cast<std::size_t>(t % 2);
      freshness.arrived(tip, now, now);
      (void)freshness.live(1 - tip, now, now);
      (void)freshness.stale(tip, now);
      (void)start.check(now, t > 10,
                        {static_cast<std::uint64_t>(t), static_cast<std::uint64_t>(t)});
      if (t % 50 == 0) link.command_sent(control::Command::move(m), now, true);
      if (t % 50 == 1) link.command_sent(control::Command::velocities(v), now, true);
      const ArmLink::StateHeard h = link.arm_state(t % 100 > 90, now);
      resent += (h.motion ? 1U : 0U) + (h.velocities ? 1U : 0U);
      if (link.due(now).heartbeat) link.heartbeat_sent(now, true);
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_GT(resent, 100U);  // the resend path ran
  EXPECT_TRUE(start.started());
}

}  // namespace
}  // namespace tactile::hand
