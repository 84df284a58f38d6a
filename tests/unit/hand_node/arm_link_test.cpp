// ArmLink, hand_node's end of the arm link, with time as an argument: no clock, no socket. Each
// case is a table of (time, what happened) -> what hand_node is to send and to say: heartbeats
// when nothing went out, the motion and the finger velocities sent again after the arm
// controller's deadman held the arm (and nothing after a Hold, Open or Stop), the arm controller
// silent, heard again and lost, and one log line per hold.
#include "arm_link.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <span>

namespace tactile::hand {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr ArmLinkTiming kTiming{10 * kMs, 100 * kMs, 500 * kMs};

enum class In {
  kTurn,           // a turn of hand_node's loop: due()
  kSent,           // the row's command went out
  kBlocked,        // the row's command could not be queued
  kHeartbeatSent,  // a Heartbeat went out
  kHeartbeatBlocked,
  kState,         // an ArmState without a fault
  kDeadmanState,  // an ArmState with ARM_FAULT_DEADMAN
  kArmHeartbeat,  // a Heartbeat from the arm controller
};

// Every output of every call; a row expects all of them (what it does not name: false, none).
struct Out {
  bool heartbeat = false;
  bool arm_silent = false;
  bool arm_lost = false;
  bool hold_began = false;
  bool heard_again = false;
  std::uint32_t resend_segment = 0;  // the MoveTo sent again (its segment id); 0: none
  double resend_squeeze_mps = 0;     // fingertip 0's z_f velocity sent again; 0: none
};

struct Row {
  std::int64_t t_ms;
  In in;
  Out out = {};
  control::Command command = {};
};

control::Command move(std::uint32_t segment) {
  control::MoveTo m;
  m.segment_id = segment;
  return control::Command::move(m);
}

control::Command squeeze(double mps) {
  control::FingerVelocities v;
  v.velocity_mps[0].z = mps;
  v.velocity_mps[1].z = mps;
  return control::Command::velocities(v);
}

Out apply(ArmLink& link, const Row& r) {
  const std::int64_t now = r.t_ms * kMs;
  Out o;
  switch (r.in) {
    case In::kTurn: {
      const ArmLink::Due d = link.due(now);
      o.heartbeat = d.heartbeat;
      o.arm_silent = d.arm_silent;
      o.arm_lost = d.arm_lost;
      break;
    }
    case In::kSent:
    case In::kBlocked:
      link.command_sent(r.command, now, r.in == In::kSent);
      break;
    case In::kHeartbeatSent:
    case In::kHeartbeatBlocked:
      link.heartbeat_sent(now, r.in == In::kHeartbeatSent);
      break;
    case In::kState:
    case In::kDeadmanState: {
      const ArmLink::StateHeard h = link.arm_state(r.in == In::kDeadmanState, now);
      o.hold_began = h.hold_began;
      o.heard_again = h.heard_again;
      if (h.motion) {
        EXPECT_EQ(h.motion->kind, control::CommandKind::kMoveTo);
        o.resend_segment = h.motion->move_to.segment_id;
      }
      if (h.velocities) {
        EXPECT_EQ(h.velocities->kind, control::CommandKind::kFingerVelocities);
        o.resend_squeeze_mps = h.velocities->finger_velocities.velocity_mps[0].z;
      }
      break;
    }
    case In::kArmHeartbeat:
      o.heard_again = link.heartbeat_heard(now);
      break;
  }
  return o;
}

void run(std::span<const Row> rows, const ArmLinkTiming& timing = kTiming) {
  ArmLink link(timing);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    SCOPED_TRACE(testing::Message() << "row " << i << " at " << r.t_ms << " ms");
    const Out o = apply(link, r);
    EXPECT_EQ(o.heartbeat, r.out.heartbeat);
    EXPECT_EQ(o.arm_silent, r.out.arm_silent);
    EXPECT_EQ(o.arm_lost, r.out.arm_lost);
    EXPECT_EQ(o.hold_began, r.out.hold_began);
    EXPECT_EQ(o.heard_again, r.out.heard_again);
    EXPECT_EQ(o.resend_segment, r.out.resend_segment);
    EXPECT_EQ(o.resend_squeeze_mps, r.out.resend_squeeze_mps);
  }
}

TEST(ArmLink, AHeartbeatIsDueAtOnceAndThenWhenNothingWentOutForAPeriod) {
  const Row rows[] = {
      {0, In::kTurn, {.heartbeat = true}},  // announce ourselves at once
      {0, In::kHeartbeatSent},
      {9, In::kTurn},
      {10, In::kTurn, {.heartbeat = true}},
      {10, In::kHeartbeatSent},
      {15, In::kSent, {}, move(1)},  // a command is as good as a heartbeat
      {24, In::kTurn},
      {25, In::kTurn, {.heartbeat = true}},
      {25, In::kHeartbeatBlocked},  // nothing went out: still due
      {26, In::kTurn, {.heartbeat = true}},
      {26, In::kBlocked, {}, move(2)},
      {27, In::kTurn, {.heartbeat = true}},
      {27, In::kHeartbeatSent},
      {36, In::kTurn},
  };
  run(rows);
}

// With no arm controller to take it, a Heartbeat is tried again retry_ns later, not at every turn
// of the loop (hand_node spun at every poll, counting each attempt blocked); once one goes out,
// the period counts again from it.
TEST(ArmLink, AHeartbeatThatCouldNotGoOutIsTriedAgainAfterTheRetryTime) {
  constexpr ArmLinkTiming kRetry{10 * kMs, 100 * kMs, 500 * kMs, 3 * kMs};
  const Row rows[] = {
      {0, In::kTurn, {.heartbeat = true}},
      {0, In::kHeartbeatBlocked},
      {1, In::kTurn},
      {2, In::kTurn},
      {3, In::kTurn, {.heartbeat = true}},
      {3, In::kHeartbeatBlocked},
      {5, In::kTurn},
      {6, In::kTurn, {.heartbeat = true}},
      {6, In::kHeartbeatSent},
      {15, In::kTurn},
      {16, In::kTurn, {.heartbeat = true}},
      {16, In::kBlocked, {}, move(1)},  // a command that could not go out: the same
      {17, In::kTurn},
      {19, In::kTurn, {.heartbeat = true}},
      {19, In::kHeartbeatSent},
      {28, In::kTurn},
      {29, In::kTurn, {.heartbeat = true}},
  };
  run(rows, kRetry);
  ArmLink link(kRetry);
  link.heartbeat_sent(5 * kMs, false);
  EXPECT_EQ(link.heartbeat_due_ns(6 * kMs), 8 * kMs);
}

TEST(ArmLink, ThePollWaitsNoLongerThanTheNextHeartbeat) {
  ArmLink link(kTiming);
  EXPECT_EQ(link.heartbeat_due_ns(3 * kMs), 3 * kMs);  // nothing went out yet: now
  link.heartbeat_sent(5 * kMs, false);
  EXPECT_EQ(link.heartbeat_due_ns(6 * kMs), 6 * kMs);
  link.heartbeat_sent(7 * kMs, true);
  EXPECT_EQ(link.heartbeat_due_ns(8 * kMs), 17 * kMs);
  link.command_sent(move(1), 12 * kMs, true);
  EXPECT_EQ(link.heartbeat_due_ns(13 * kMs), 22 * kMs);
}

TEST(ArmLink, EveryArmStateReportingAHoldIsAnsweredWithTheMotionAndTheVelocities) {
  const Row rows[] = {
      {0, In::kState},
      {1, In::kSent, {}, move(3)},
      {2, In::kSent, {}, squeeze(0.002)},
      {50,
       In::kDeadmanState,
       {.hold_began = true, .resend_segment = 3, .resend_squeeze_mps = 0.002}},
      // The same hold reported again: answered again, logged once.
      {60, In::kDeadmanState, {.resend_segment = 3, .resend_squeeze_mps = 0.002}},
      {70, In::kState},
      // A new hold: logged again.
      {80,
       In::kDeadmanState,
       {.hold_began = true, .resend_segment = 3, .resend_squeeze_mps = 0.002}},
      // The newest of each kind is what the arm does on our word.
      {90, In::kSent, {}, move(4)},
      {91, In::kDeadmanState, {.resend_segment = 4, .resend_squeeze_mps = 0.002}},
      {92, In::kSent, {}, squeeze(-0.001)},
      {93, In::kDeadmanState, {.resend_segment = 4, .resend_squeeze_mps = -0.001}},
  };
  run(rows);
}

TEST(ArmLink, OnlyTheKindOfCommandSentIsResumed) {
  const Row motion_only[] = {
      {0, In::kSent, {}, move(5)},
      {50, In::kDeadmanState, {.hold_began = true, .resend_segment = 5}},
  };
  run(motion_only);
  const Row velocities_only[] = {
      {0, In::kSent, {}, squeeze(0.003)},
      {50, In::kDeadmanState, {.hold_began = true, .resend_squeeze_mps = 0.003}},
  };
  run(velocities_only);
  // A command the socket could not queue is still what we asked for: resumed as well.
  const Row blocked[] = {
      {0, In::kBlocked, {}, move(6)},
      {50, In::kDeadmanState, {.hold_began = true, .resend_segment = 6}},
  };
  run(blocked);
}

TEST(ArmLink, AfterAHoldAnOpenOrAStopThereIsNothingToResume) {
  const control::Command open = control::Command::open_fingers({0.01, 0.004});
  for (const control::Command& c : {control::Command::hold(), open, control::Command::stop()}) {
    SCOPED_TRACE(static_cast<int>(c.kind));
    const Row rows[] = {
        {0, In::kSent, {}, move(7)},
        {1, In::kSent, {}, squeeze(0.002)},
        {2, In::kSent, {}, c},
        {50, In::kDeadmanState, {.hold_began = true}},  // logged, nothing sent
        {60, In::kState},
        // The next motion after it is resumed alone: the velocities were forgotten.
        {61, In::kSent, {}, move(8)},
        {100, In::kDeadmanState, {.hold_began = true, .resend_segment = 8}},
    };
    run(rows);
  }
}

TEST(ArmLink, NoneIsNotACommandAndForgetsNothing) {
  const Row rows[] = {
      {0, In::kSent, {}, move(9)},
      {1, In::kSent, {}, control::Command::none()},
      {50, In::kDeadmanState, {.hold_began = true, .resend_segment = 9}},
  };
  run(rows);
}

TEST(ArmLink, ASilentArmControllerIsReportedOnceAndHeardAgain) {
  const Row rows[] = {
      {0, In::kTurn, {.heartbeat = true}},
      {0, In::kHeartbeatSent},
      {5, In::kState},
      {105, In::kTurn, {.heartbeat = true}},  // exactly arm_timeout_s: not yet
      {105, In::kHeartbeatSent},
      {106, In::kTurn, {.arm_silent = true}},
      {110, In::kTurn},  // once per silence
      {200, In::kState, {.heard_again = true}},
      {250, In::kState},
      {351, In::kTurn, {.heartbeat = true, .arm_silent = true}},
      // Its heartbeats are words too.
      {360, In::kArmHeartbeat, {.heard_again = true}},
      {361, In::kArmHeartbeat},
      {461, In::kTurn, {.heartbeat = true}},
      {462, In::kTurn, {.heartbeat = true, .arm_silent = true}},
  };
  run(rows);
}

TEST(ArmLink, AnArmControllerSilentPastArmLostIsLost) {
  const Row rows[] = {
      {0, In::kState},
      {0, In::kHeartbeatSent},
      {101, In::kTurn, {.heartbeat = true, .arm_silent = true}},
      {101, In::kHeartbeatSent},
      {500, In::kTurn, {.heartbeat = true}},  // exactly arm_lost_s: not yet
      {500, In::kHeartbeatSent},
      {501, In::kTurn, {.arm_lost = true}},
  };
  run(rows);
  // Heard just before: the count starts again.
  const Row heard[] = {
      {0, In::kState},
      {0, In::kHeartbeatSent},
      {499, In::kArmHeartbeat},
      {499, In::kHeartbeatSent},
      {501, In::kTurn},
      {999, In::kHeartbeatSent},
      {1000, In::kTurn, {.arm_silent = true, .arm_lost = true}},
  };
  run(heard);
}

TEST(ArmLink, ArmLostZeroNeverGivesUp) {
  const Row rows[] = {
      {0, In::kState},
      {3'600'000, In::kTurn, {.heartbeat = true, .arm_silent = true}},  // an hour
      {3'600'001, In::kTurn, {.heartbeat = true}},
  };
  run(rows, {10 * kMs, 100 * kMs, 0});
}

TEST(ArmLink, BeforeTheFirstArmStateItWaitsHoweverLongItTakes) {
  ArmLink link(kTiming);
  EXPECT_FALSE(link.arm_heard());
  const Row rows[] = {
      {0, In::kHeartbeatSent},
      {5, In::kArmHeartbeat},  // heard, but not yet answering: no silence is counted
      {10'000, In::kTurn, {.heartbeat = true}},
      {10'000, In::kHeartbeatSent},
      {10'001, In::kState},
      {10'101, In::kTurn, {.heartbeat = true}},
      {10'101, In::kHeartbeatSent},
      {10'102, In::kTurn, {.arm_silent = true}},
  };
  run(rows);
  link.arm_state(false, 0);
  EXPECT_TRUE(link.arm_heard());
}

TEST(ArmLink, TheSilenceIsMeasuredFromTheLastWord) {
  ArmLink link(kTiming);
  link.arm_state(false, 40 * kMs);
  link.heartbeat_heard(60 * kMs);
  const ArmLink::Due d = link.due(200 * kMs);
  EXPECT_TRUE(d.arm_silent);
  EXPECT_EQ(d.silent_ns, 140 * kMs);
}

}  // namespace
}  // namespace tactile::hand
