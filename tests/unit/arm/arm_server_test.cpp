// ArmServer over real sockets (tcp://127.0.0.1:*) with a backend that records what it is handed:
// the deadman trips once, strangers and garbage are refused and counted, CURVE lets in only the
// listed clients. Time is the test's: every call gets the instant it is for.
#include "tactile/arm/arm_server.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile::arm {
namespace {

using namespace std::chrono_literals;

constexpr std::int64_t kMs = 1'000'000;
const wire::FingertipIds kIds{"left", "right"};

struct RecordingArm final : ArmBackend {
  wire::ArmStateData read(std::int64_t now_ns) override {
    wire::ArmStateData s;
    s.time_ns = now_ns;
    s.active_segment_id = 7;
    return s;
  }
  bool write(const wire::ReceivedCommand& c, std::int64_t) override {
    written.push_back(c.command.kind);
    return accept;
  }
  void hold(std::int64_t now_ns) override { holds.push_back(now_ns); }

  std::vector<control::CommandKind> written;
  std::vector<std::int64_t> holds;
  bool accept = true;
};

std::string heartbeat() {
  v1::Envelope e;
  e.mutable_heartbeat()->set_sender("test");
  std::string out;
  wire::encode(e, out);
  return out;
}

std::string command(const control::Command& c, std::uint64_t sequence) {
  v1::Envelope e;
  wire::fill_arm_command(c, sequence, 1, {}, kIds, *e.mutable_arm_command());
  std::string out;
  wire::encode(e, out);
  return out;
}

ArmServerOptions options() {
  ArmServerOptions o;
  o.endpoint = "tcp://127.0.0.1:*";
  o.deadman_s = 0.04;
  o.heartbeat_period_s = 0;
  o.fingertip_ids = kIds;
  return o;
}

// Each test's context and recording backend.
class ArmServerOverSockets : public ::testing::Test {
 protected:
  zmq::context_t ctx;
  RecordingArm arm;
};

// Waits (up to 2 s of real time) until the server has a message, and handles it at `now_ns`.
bool serve_next(ArmServer& server, std::int64_t now_ns) {
  std::array<zmq::socket_ref, 1> s{server.socket()};
  for (int i = 0; i < 40; ++i) {
    if (server.serve_one(now_ns)) return true;
    wire::poll_readable(s, 50ms);
  }
  return false;
}

// The next ArmState the client receives within `timeout`.
std::optional<v1::ArmState> state_at(wire::Dealer& client, std::chrono::milliseconds timeout) {
  std::vector<std::uint8_t> bytes;
  v1::Envelope e;
  while (client.receive(bytes, timeout)) {
    if (wire::decode(bytes, e) == wire::DecodeStatus::kOk && e.has_arm_state())
      return e.arm_state();
  }
  return std::nullopt;
}

bool has_fault(const v1::ArmState& s, v1::ArmFault f) {
  return std::find(s.faults().begin(), s.faults().end(), f) != s.faults().end();
}

TEST_F(ArmServerOverSockets, CommandsReachTheBackendAndTheStateNamesTheLast) {
  ArmServer server(ctx, options(), arm);
  wire::Dealer hand(ctx, server.endpoint());
  EXPECT_FALSE(server.send_state(0));  // nobody to answer yet
  ASSERT_TRUE(hand.send(wire::bytes_of(command(control::Command::hold(), 41))));
  ASSERT_TRUE(serve_next(server, 10 * kMs));
  ASSERT_EQ(arm.written, std::vector<control::CommandKind>{control::CommandKind::kHold});
  ASSERT_TRUE(server.send_state(11 * kMs));
  const auto s = state_at(hand, 2000ms);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->last_command_sequence(), 41U);
  EXPECT_EQ(s->active_segment_id(), 7U);
  EXPECT_EQ(s->time_ns(), 11 * kMs);
  EXPECT_FALSE(has_fault(*s, v1::ARM_FAULT_DEADMAN));
  EXPECT_EQ(server.counters().commands, 1U);
  EXPECT_EQ(server.counters().refused(), 0U);
}

TEST_F(ArmServerOverSockets, TheDeadmanTripsOnceAndTheStatesSaySoUntilACommand) {
  ArmServer server(ctx, options(), arm);
  wire::Dealer hand(ctx, server.endpoint());
  server.check_deadman(10'000 * kMs);  // no peer yet: no deadman
  ASSERT_TRUE(hand.send(wire::bytes_of(heartbeat())));
  ASSERT_TRUE(serve_next(server, 100 * kMs));
  server.check_deadman(140 * kMs);  // exactly the deadman: alive
  EXPECT_TRUE(arm.holds.empty());
  server.check_deadman(141 * kMs);
  server.check_deadman(200 * kMs);
  ASSERT_TRUE(server.send_state(300 * kMs));
  EXPECT_EQ(arm.holds, std::vector<std::int64_t>{141 * kMs});
  EXPECT_EQ(server.counters().deadman_trips, 1U);
  const auto held = state_at(hand, 2000ms);
  ASSERT_TRUE(held);
  EXPECT_TRUE(has_fault(*held, v1::ARM_FAULT_DEADMAN));
  // A heartbeat does not end the hold; a command does.
  ASSERT_TRUE(hand.send(wire::bytes_of(heartbeat())));
  ASSERT_TRUE(serve_next(server, 310 * kMs));
  EXPECT_TRUE(server.peer().held());
  ASSERT_TRUE(hand.send(wire::bytes_of(command(control::Command::hold(), 1))));
  ASSERT_TRUE(serve_next(server, 320 * kMs));
  EXPECT_FALSE(server.peer().held());
  ASSERT_TRUE(server.send_state(330 * kMs));
  const auto resumed = state_at(hand, 2000ms);
  ASSERT_TRUE(resumed);
  EXPECT_FALSE(has_fault(*resumed, v1::ARM_FAULT_DEADMAN));
}

// The hold's only report is the DEADMAN fault: a command that ends the hold before the next
// state (hand_node's velocity change, sent while it did not know) must not swallow it, or the
// motion the hold stopped is never sent again (a sanitizer CI run's lowering "timed out").
TEST_F(ArmServerOverSockets, AHoldACommandEndedBeforeAnyStateIsStillReportedOnce) {
  ArmServer server(ctx, options(), arm);
  wire::Dealer hand(ctx, server.endpoint());
  ASSERT_TRUE(hand.send(wire::bytes_of(heartbeat())));
  ASSERT_TRUE(serve_next(server, 100 * kMs));
  server.check_deadman(141 * kMs);
  ASSERT_EQ(arm.holds.size(), 1U);
  ASSERT_TRUE(hand.send(wire::bytes_of(command(control::Command::hold(), 1))));
  ASSERT_TRUE(serve_next(server, 150 * kMs));
  EXPECT_FALSE(server.peer().held());
  ASSERT_TRUE(server.send_state(160 * kMs));
  const auto first = state_at(hand, 2000ms);
  ASSERT_TRUE(first);
  EXPECT_TRUE(has_fault(*first, v1::ARM_FAULT_DEADMAN));
  ASSERT_TRUE(server.send_state(170 * kMs));
  const auto second = state_at(hand, 2000ms);
  ASSERT_TRUE(second);
  EXPECT_FALSE(has_fault(*second, v1::ARM_FAULT_DEADMAN));
}

TEST_F(ArmServerOverSockets, AStrangersHeartbeatIsRefusedWhileThePeerIsAlive) {
  ArmServer server(ctx, options(), arm);
  wire::Dealer hand(ctx, server.endpoint());
  wire::Dealer stranger(ctx, server.endpoint());
  ASSERT_TRUE(hand.send(wire::bytes_of(heartbeat())));
  ASSERT_TRUE(serve_next(server, 0));
  const std::string peer = server.peer().peer();
  ASSERT_TRUE(stranger.send(wire::bytes_of(heartbeat())));
  ASSERT_TRUE(serve_next(server, 10 * kMs));
  EXPECT_EQ(server.counters().strangers, 1U);
  EXPECT_EQ(server.peer().peer(), peer);
  // The stranger's words do not keep the arm going, and it is not answered.
  server.check_deadman(41 * kMs);
  EXPECT_EQ(arm.holds.size(), 1U);
  ASSERT_TRUE(server.send_state(50 * kMs));
  EXPECT_TRUE(state_at(hand, 2000ms));
  EXPECT_FALSE(state_at(stranger, 100ms));
}

TEST_F(ArmServerOverSockets, GarbageAndBadCommandsAreCountedAndNeverReachTheArm) {
  ArmServer server(ctx, options(), arm);
  wire::Dealer client(ctx, server.endpoint());
  const std::string junk = "\x08\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff not an envelope";
  v1::Envelope frame;  // decodable, but not for the arm
  frame.mutable_tactile_frame()->set_sensor_id("left");
  std::string not_for_arm;
  wire::encode(frame, not_for_arm);
  control::Command nan_open = control::Command::open_fingers({0.01, 0.004});
  nan_open.open.speed_mps = std::numeric_limits<double>::quiet_NaN();
  for (const std::string& m : {junk, not_for_arm, command(nan_open, 1)}) {
    ASSERT_TRUE(client.send(wire::bytes_of(m)));
    ASSERT_TRUE(serve_next(server, 0));
  }
  const ArmServerCounters c = server.counters();
  EXPECT_EQ(c.garbage, 2U);
  EXPECT_EQ(c.invalid_commands, 1U);
  EXPECT_EQ(c.refused(), 3U);
  EXPECT_EQ(c.commands, 0U);
  EXPECT_TRUE(arm.written.empty());
  EXPECT_FALSE(server.peer().has_peer());  // garbage never makes a peer
  // A command the backend refuses is counted too.
  arm.accept = false;
  ASSERT_TRUE(client.send(wire::bytes_of(command(control::Command::hold(), 2))));
  ASSERT_TRUE(serve_next(server, 0));
  EXPECT_EQ(server.counters().invalid_commands, 2U);
}

TEST_F(ArmServerOverSockets, HeartbeatsGoToThePeerWhenNothingElseDid) {
  ArmServerOptions o = options();
  o.heartbeat_period_s = 0.1;
  ArmServer server(ctx, o, arm);
  wire::Dealer hand(ctx, server.endpoint());
  ASSERT_TRUE(hand.send(wire::bytes_of(heartbeat())));
  ASSERT_TRUE(serve_next(server, 1000 * kMs));
  server.heartbeat_if_quiet(1000 * kMs);
  ASSERT_TRUE(server.send_state(1010 * kMs));
  server.heartbeat_if_quiet(1100 * kMs);  // a state went 90 ms ago: not yet
  EXPECT_EQ(server.counters().heartbeats_sent, 1U);
  server.heartbeat_if_quiet(1110 * kMs);
  EXPECT_EQ(server.counters().heartbeats_sent, 2U);
}

TEST_F(ArmServerOverSockets, BadSettingsThrowAtStartUp) {
  ArmServerOptions o = options();
  o.deadman_s = 0;
  EXPECT_THROW(ArmServer(ctx, o, arm), std::invalid_argument);
  o = options();
  o.heartbeat_period_s = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ArmServer(ctx, o, arm), std::invalid_argument);
  o = options();
  o.endpoint = "tcp://no-such-host.invalid:1";
  EXPECT_THROW(ArmServer(ctx, o, arm), std::exception);
}

TEST_F(ArmServerOverSockets, UnderCurveAClientNotInTheListIsRefused) {
  if (!wire::curve_available()) GTEST_FAIL() << "libzmq without CURVE";
  const wire::CurveKeyPair arm_keys = wire::generate_keypair();
  const wire::CurveKeyPair hand_keys = wire::generate_keypair();
  const wire::CurveKeyPair other_keys = wire::generate_keypair();
  ArmServerOptions o = options();
  o.security = wire::ServerSecurity{arm_keys, {hand_keys.public_z85}};
  ArmServer server(ctx, o, arm);
  // It knows the arm's public key, but its own key is not in the list.
  const wire::ClientSecurity other{other_keys, arm_keys.public_z85};
  wire::Dealer intruder(ctx, server.endpoint(), &other);
  (void)intruder.send(wire::bytes_of(command(control::Command::hold(), 1)));
  EXPECT_FALSE(serve_next(server, 0));
  EXPECT_GE(server.refused_clients(), 1U);
  EXPECT_TRUE(arm.written.empty());
  const wire::ClientSecurity hand_sec{hand_keys, arm_keys.public_z85};
  wire::Dealer hand(ctx, server.endpoint(), &hand_sec);
  ASSERT_TRUE(hand.send(wire::bytes_of(command(control::Command::hold(), 2))));
  ASSERT_TRUE(serve_next(server, 0));
  EXPECT_EQ(arm.written.size(), 1U);
}

}  // namespace
}  // namespace tactile::arm
