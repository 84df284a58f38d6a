// hand_node with CURVE on both links, as a real process: TactileFrames from a publisher that does
// not hold the sensor's key never reach the controller.
#include "tactile/wire/security.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "process.hpp"
#include "synthetic.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;

const wire::FingertipIds kIds{"left", "right"};
constexpr std::uint64_t kIntruderSequence = 1'000'000;

class SecuredHandNode : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::SceneOptions o;
    o.width = 96;
    o.height = 64;
    for (const auto& id : kIds) {
      Calibration cal = testing::grid_calibration(o, 3, 1, 30, 12);
      cal.sensor_id = id;
      config::save_calibration(dir_ / (id + ".yaml"), cal);
      cals_.push_back(cal);
    }
    for (const char* name : {"sensor", "hand", "arm", "intruder"}) {
      wire::write_key_files(dir_ / "keys", name, wire::generate_keypair());
    }
    std::ofstream(dir_ / "hand.yaml") << "format: tactile-hand/1\n"
                                         "fingertips:\n"
                                         "  - {sensor_id: left, calibration: left.yaml}\n"
                                         "  - {sensor_id: right, calibration: right.yaml}\n"
                                         "heartbeat_period_s: 0.05\n"
                                         "security:\n"
                                         "  secret_key: keys/hand.key\n"
                                         "  sensor_public_key: keys/sensor.pub\n"
                                         "  arm_public_key: keys/arm.pub\n";
  }

  void publish(wire::Publisher& pub, std::uint64_t sequence) {
    std::vector<ElementReading> readings(3);
    for (std::size_t t = 0; t < 2; ++t) {
      for (std::size_t e = 0; e < 3; ++e)
        readings[e].id = cals_[t].elements[e].id;
      wire::FrameHeader h;
      h.sequence = sequence;
      h.status = v1::FRAME_STATUS_COMPLETE;
      wire::fill_tactile_frame(kIds[t], h, readings, cals_[t].mm_per_px,
                               *env_.mutable_tactile_frame());
      wire::encode(env_, out_);
      pub.send(wire::frame_topic(kIds[t]), wire::bytes_of(out_));
    }
  }

  testing::TempDir dir_;
  std::vector<Calibration> cals_;
  v1::Envelope env_;
  std::string out_;
};

TEST_F(SecuredHandNode, TakesFramesOnlyFromTheSensorItHasTheKeyOf) {
  zmq::context_t ctx;
  const wire::ServerSecurity arm_sec{wire::load_key_pair(dir_ / "keys/arm.key"),
                                     {wire::load_public_key(dir_ / "keys/hand.pub")}};
  wire::Router arm(ctx, "tcp://127.0.0.1:*", &arm_sec);
  const wire::ServerSecurity intruder_sec{wire::load_key_pair(dir_ / "keys/intruder.key"), {}};
  wire::Publisher intruder(ctx, "tcp://127.0.0.1:*", &intruder_sec);
  const wire::ServerSecurity sensor_sec{wire::load_key_pair(dir_ / "keys/sensor.key"), {}};
  wire::Publisher sensor(ctx, "tcp://127.0.0.1:*", &sensor_sec);

  testing::Process hand({TACTILE_HAND_NODE_PATH, "--config", (dir_ / "hand.yaml").string(),
                         "--subscribe", intruder.endpoint(), "--subscribe", sensor.endpoint(),
                         "--arm", arm.endpoint()});
  std::string peer;
  std::vector<std::uint8_t> payload;
  v1::Envelope env;
  wire::ReceivedCommand cmd;
  wire::ArmStateData state;
  std::uint64_t heartbeats = 0;
  std::uint64_t commands = 0;
  std::uint64_t intruder_answers = 0;
  const auto exchange = [&](bool legit_publishes, std::chrono::milliseconds span) {
    const auto end = std::chrono::steady_clock::now() + span;
    std::uint64_t seq = 0;
    while (std::chrono::steady_clock::now() < end) {
      publish(intruder, kIntruderSequence + seq);
      if (legit_publishes) publish(sensor, seq);
      ++seq;
      while (arm.receive(peer, payload, 10ms)) {
        if (wire::decode(payload, env) != wire::DecodeStatus::kOk) continue;
        if (env.has_heartbeat()) ++heartbeats;
        if (env.has_arm_command() &&
            wire::read_arm_command(env.arm_command(), kIds, cmd) == wire::DecodeStatus::kOk) {
          ++commands;
          for (std::size_t i = 0; i < cmd.answers.count; ++i) {
            intruder_answers += cmd.answers.refs[i].sequence >= kIntruderSequence ? 1 : 0;
          }
        }
        wire::fill_arm_state(state, kIds, *env.mutable_arm_state());
        std::string out;
        wire::encode(env, out);
        arm.send(peer, wire::bytes_of(out));
      }
    }
  };
  // Only the intruder publishes: the arm link works (heartbeats), but the task never starts.
  exchange(false, 1500ms);
  EXPECT_GT(heartbeats, 0U) << hand.err_so_far();
  EXPECT_EQ(commands, 0U) << hand.err_so_far();
  // The real sensor publishes too: the task starts, on its frames alone.
  exchange(true, 1500ms);
  EXPECT_GT(commands, 0U) << hand.err_so_far();
  EXPECT_EQ(intruder_answers, 0U);
  hand.signal(SIGTERM);
  EXPECT_EQ(hand.wait(10s).exit_code, 0);
}

// The events PUB is a CURVE server with hand_node's own key: a subscriber that knows hand_node's
// public key receives the run's messages (the ArmStates it copies there), one without keys and
// one that expects another key receive nothing.
TEST_F(SecuredHandNode, EventsReachOnlySubscribersThatKnowItsKey) {
  zmq::context_t ctx;
  const wire::ServerSecurity arm_sec{wire::load_key_pair(dir_ / "keys/arm.key"),
                                     {wire::load_public_key(dir_ / "keys/hand.pub")}};
  wire::Router arm(ctx, "tcp://127.0.0.1:*", &arm_sec);
  const std::string events_endpoint = "ipc://" + (dir_ / "events").string();
  testing::Process hand({TACTILE_HAND_NODE_PATH, "--config", (dir_ / "hand.yaml").string(), "--arm",
                         arm.endpoint(), "--events", events_endpoint});
  const wire::CurveKeyPair recorder_keys = wire::generate_keypair();
  const wire::ClientSecurity knows{recorder_keys, wire::load_public_key(dir_ / "keys/hand.pub")};
  const wire::ClientSecurity fooled{recorder_keys,
                                    wire::load_public_key(dir_ / "keys/intruder.pub")};
  const std::vector<std::string> topics{""};
  wire::Subscriber good(ctx, {events_endpoint}, topics, &knows);
  wire::Subscriber wrong(ctx, {events_endpoint}, topics, &fooled);
  wire::Subscriber plain(ctx, {events_endpoint}, topics);

  std::string peer;
  std::vector<std::uint8_t> payload;
  v1::Envelope env;
  wire::ArmStateData state;
  std::string out;
  wire::TopicMessage m;
  std::uint64_t to_good = 0;
  std::uint64_t to_others = 0;
  const auto end = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < end) {
    // Answer each heartbeat with an ArmState, which hand_node copies onto its events.
    while (arm.receive(peer, payload, 10ms)) {
      wire::fill_arm_state(state, kIds, *env.mutable_arm_state());
      wire::encode(env, out);
      arm.send(peer, wire::bytes_of(out));
    }
    while (good.receive(m, 0ms))
      to_good += m.topic == wire::kArmTopic ? 1 : 0;
    while (wrong.receive(m, 0ms) || plain.receive(m, 0ms))
      ++to_others;
  }
  EXPECT_GT(to_good, 0U) << hand.err_so_far();
  EXPECT_EQ(to_others, 0U);
  hand.signal(SIGTERM);
  EXPECT_EQ(hand.wait(10s).exit_code, 0);
}

TEST_F(SecuredHandNode, RefusesAReadableSecretKey) {
  ::chmod((dir_ / "keys/hand.key").c_str(), 0640);
  const auto r = testing::run({TACTILE_HAND_NODE_PATH, "--config", (dir_ / "hand.yaml").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("security.secret_key"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("chmod 600"), std::string::npos) << r.err;
  const wire::CurveKeyPair k = wire::load_key_pair(
      (::chmod((dir_ / "keys/hand.key").c_str(), 0600), dir_ / "keys/hand.key"));
  EXPECT_EQ(r.err.find(k.secret_z85), std::string::npos);
}

}  // namespace
}  // namespace tactile
