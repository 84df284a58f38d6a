// Who the arm answers and its deadman (docs/arm.md, "Timing"), with time as an argument: no
// clock, no socket.
#include "tactile/arm/arm_peer.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace tactile::arm {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kDeadman = 40 * kMs;

TEST(ArmPeer, NoPeerNoDeadman) {
  ArmPeer p(kDeadman);
  EXPECT_FALSE(p.has_peer());
  EXPECT_FALSE(p.deadman_trips(10'000 * kMs));
  EXPECT_FALSE(p.held());
}

TEST(ArmPeer, TheFirstClientThatSpeaksIsThePeer) {
  ArmPeer p(kDeadman);
  const ArmPeer::Heard h = p.heartbeat("hand", 5 * kMs);
  EXPECT_TRUE(h.accepted);
  EXPECT_TRUE(h.connected);
  EXPECT_FALSE(h.new_client);
  EXPECT_TRUE(p.has_peer());
  EXPECT_EQ(p.peer(), "hand");
  EXPECT_EQ(p.last_heard_ns(), 5 * kMs);
  EXPECT_FALSE(p.heartbeat("hand", 6 * kMs).connected);
}

TEST(ArmPeer, TripsOnceJustAfterTheDeadman) {
  ArmPeer p(kDeadman);
  p.command("hand", 100 * kMs);
  EXPECT_FALSE(p.deadman_trips(100 * kMs + kDeadman));  // exactly the deadman: still alive
  EXPECT_TRUE(p.deadman_trips(100 * kMs + kDeadman + 1));
  EXPECT_TRUE(p.held());
  EXPECT_FALSE(p.deadman_trips(200 * kMs));  // once per silence
  EXPECT_TRUE(p.held());
}

TEST(ArmPeer, HeartbeatsKeepTheArmGoing) {
  ArmPeer p(kDeadman);
  p.command("hand", 0);
  for (std::int64_t t = 10 * kMs; t <= 1000 * kMs; t += 10 * kMs) {
    EXPECT_TRUE(p.heartbeat("hand", t).accepted);
    EXPECT_FALSE(p.deadman_trips(t + 30 * kMs)) << t;
  }
  EXPECT_FALSE(p.held());
}

TEST(ArmPeer, AnotherClientsHeartbeatIsRefusedWhileThePeerIsAlive) {
  ArmPeer p(kDeadman);
  p.heartbeat("hand", 0);
  const ArmPeer::Heard h = p.heartbeat("intruder", 10 * kMs);
  EXPECT_FALSE(h.accepted);
  EXPECT_EQ(p.peer(), "hand");
  EXPECT_EQ(p.last_heard_ns(), 0);  // the intruder's words do not keep the arm going
  EXPECT_TRUE(p.deadman_trips(kDeadman + 1));
}

TEST(ArmPeer, ANewClientTakesOverAfterTheDeadmanHold) {
  ArmPeer p(kDeadman);
  p.command("old", 0);
  ASSERT_TRUE(p.deadman_trips(kDeadman + 1));
  const ArmPeer::Heard h = p.heartbeat("new", 100 * kMs);
  EXPECT_TRUE(h.accepted);
  EXPECT_TRUE(h.new_client);
  EXPECT_EQ(p.peer(), "new");
  EXPECT_TRUE(p.held());  // the hold lasts until a command
  const ArmPeer::Heard c = p.command("new", 110 * kMs);
  EXPECT_TRUE(c.resumed);
  EXPECT_FALSE(c.new_client);
  EXPECT_FALSE(p.held());
}

TEST(ArmPeer, ACommandFromAnotherClientMakesItThePeer) {
  ArmPeer p(kDeadman);
  p.heartbeat("a", 0);
  const ArmPeer::Heard c = p.command("b", 10 * kMs);
  EXPECT_TRUE(c.accepted);
  EXPECT_TRUE(c.new_client);
  EXPECT_FALSE(c.resumed);
  EXPECT_EQ(p.peer(), "b");
  EXPECT_EQ(p.last_heard_ns(), 10 * kMs);
}

TEST(ArmPeer, TheSamePeerCommandingAgainEndsTheHold) {
  ArmPeer p(kDeadman);
  p.command("hand", 0);
  ASSERT_TRUE(p.deadman_trips(50 * kMs));
  EXPECT_TRUE(p.heartbeat("hand", 60 * kMs).accepted);
  EXPECT_TRUE(p.held());  // a heartbeat does not end it
  EXPECT_TRUE(p.command("hand", 70 * kMs).resumed);
  EXPECT_FALSE(p.held());
  EXPECT_FALSE(p.deadman_trips(70 * kMs + kDeadman));
  EXPECT_TRUE(p.deadman_trips(70 * kMs + kDeadman + 1));
}

// A hold is reported by at least one ArmState even when a command ends it first (the client had
// sent a velocity change meanwhile): the stopped motion must be sent again, and only the report
// says so. Reported once; a hold still on is reported by every state.
TEST(ArmPeer, EveryHoldIsReportedAtLeastOnceEvenWhenACommandEndsItFirst) {
  ArmPeer p(kDeadman);
  p.command("hand", 0);
  EXPECT_FALSE(p.report_deadman());
  ASSERT_TRUE(p.deadman_trips(50 * kMs));
  EXPECT_TRUE(p.command("hand", 55 * kMs).resumed);  // before any state
  EXPECT_FALSE(p.held());
  EXPECT_TRUE(p.report_deadman());
  EXPECT_FALSE(p.report_deadman());
  ASSERT_TRUE(p.deadman_trips(55 * kMs + kDeadman + 1));
  EXPECT_TRUE(p.report_deadman());
  EXPECT_TRUE(p.report_deadman());  // still held
  p.command("hand", 200 * kMs);
  EXPECT_FALSE(p.report_deadman());  // this hold was reported
}

}  // namespace
}  // namespace tactile::arm
