// CURVE on both links, over real TCP sockets: who can publish to a subscriber, who can command
// a router, and the key files.
#include "tactile/wire/security.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>

#include "process.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile::wire {
namespace {

using namespace std::chrono_literals;

// Publishes until the subscriber gets a message or the attempts run out (bounded).
bool delivered(Publisher& pub, Subscriber& sub, int attempts = 100) {
  TopicMessage m;
  for (int i = 0; i < attempts; ++i) {
    pub.send(frame_topic("left"), bytes_of("payload"));
    if (sub.receive(m, 10ms)) return true;
  }
  return false;
}

// A client that knows the arm's public key but is not in its list: nothing it sends arrives.
bool refuses_a_stranger(zmq::context_t& ctx, Router& arm, const std::string& arm_public_z85) {
  const ClientSecurity stranger{generate_keypair(), arm_public_z85};
  Dealer intruder(ctx, arm.endpoint(), &stranger);
  intruder.send(bytes_of("stop everything"));
  std::string peer;
  std::vector<std::uint8_t> payload;
  return !arm.receive(peer, payload, 500ms) && arm.refused_clients() >= 1;
}

TEST(Curve, IsAvailable) {
  EXPECT_TRUE(curve_available());
}

TEST(Curve, SubscriberTakesDataOnlyFromThePublisherWhoseKeyItKnows) {
  zmq::context_t ctx;
  const ServerSecurity sensor{generate_keypair(), {}};
  const ServerSecurity intruder{generate_keypair(), {}};
  const ClientSecurity hand{generate_keypair(), sensor.keys.public_z85};

  Publisher good(ctx, "tcp://127.0.0.1:*", &sensor);
  Subscriber sub(ctx, {good.endpoint()}, {kFrameTopicPrefix}, &hand);
  EXPECT_TRUE(delivered(good, sub));

  // A publisher with another key, where the subscriber connects: the handshake fails.
  Publisher bad(ctx, "tcp://127.0.0.1:*", &intruder);
  Subscriber fooled(ctx, {bad.endpoint()}, {kFrameTopicPrefix}, &hand);
  EXPECT_FALSE(delivered(bad, fooled, 50));
  // A publisher without CURVE: nothing either.
  Publisher plain(ctx, "tcp://127.0.0.1:*");
  Subscriber strict(ctx, {plain.endpoint()}, {kFrameTopicPrefix}, &hand);
  EXPECT_FALSE(delivered(plain, strict, 50));
  // And a subscriber without keys gets nothing from a secured publisher.
  Subscriber outsider(ctx, {good.endpoint()}, {kFrameTopicPrefix});
  EXPECT_FALSE(delivered(good, outsider, 50));
}

TEST(Curve, RouterTakesCommandsOnlyFromAuthorizedClients) {
  zmq::context_t ctx;
  const CurveKeyPair arm_keys = generate_keypair();
  const CurveKeyPair hand_keys = generate_keypair();
  const ServerSecurity arm_sec{arm_keys, {hand_keys.public_z85}};
  Router arm(ctx, "tcp://127.0.0.1:*", &arm_sec);

  EXPECT_TRUE(refuses_a_stranger(ctx, arm, arm_keys.public_z85));
  std::string peer;
  std::vector<std::uint8_t> payload;

  Dealer no_keys(ctx, arm.endpoint());
  no_keys.send(bytes_of("hello"));
  EXPECT_FALSE(arm.receive(peer, payload, 300ms));

  const ClientSecurity hand{hand_keys, arm_keys.public_z85};
  Dealer client(ctx, arm.endpoint(), &hand);
  ASSERT_TRUE(client.send(bytes_of("command")));
  ASSERT_TRUE(arm.receive(peer, payload, 2000ms));
  EXPECT_EQ(std::string(payload.begin(), payload.end()), "command");
  ASSERT_TRUE(arm.send(peer, bytes_of("state")));
  ASSERT_TRUE(client.receive(payload, 2000ms));
  EXPECT_EQ(std::string(payload.begin(), payload.end()), "state");
}

// The rig's process holds the arm's ROUTER, with its client list, and the ground-truth PUB, which
// lets in whoever knows its key: one context has one authentication handler, and the arm's list
// must not shut out the PUB's subscribers (nor let a plain one in).
TEST(Curve, AnOpenPublisherBesideAListedRouterAdmitsEveryClientThatKnowsItsKey) {
  zmq::context_t ctx;
  const CurveKeyPair arm_keys = generate_keypair();
  const ServerSecurity arm_sec{arm_keys, {generate_keypair().public_z85}};
  Router arm(ctx, "tcp://127.0.0.1:*", &arm_sec);
  const ServerSecurity truth_sec{generate_keypair(), {}};
  Publisher truth(ctx, "tcp://127.0.0.1:*", &truth_sec);

  const ClientSecurity recorder{generate_keypair(), truth_sec.keys.public_z85};
  Subscriber sub(ctx, {truth.endpoint()}, {kFrameTopicPrefix}, &recorder);
  EXPECT_TRUE(delivered(truth, sub));
  Subscriber outsider(ctx, {truth.endpoint()}, {kFrameTopicPrefix});
  EXPECT_FALSE(delivered(truth, outsider, 50));

  // The router's list still holds.
  EXPECT_TRUE(refuses_a_stranger(ctx, arm, arm_keys.public_z85));
}

TEST(KeyFiles, RoundTripWithTheRightPermissions) {
  testing::TempDir dir;
  const CurveKeyPair k = generate_keypair();
  write_key_files(dir.path(), "hand", k);
  struct stat st {};
  ASSERT_EQ(::stat((dir / "hand.key").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600U);
  ASSERT_EQ(::stat((dir / "hand.pub").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644U);
  const CurveKeyPair back = load_key_pair(dir / "hand.key");
  EXPECT_EQ(back.public_z85, k.public_z85);
  EXPECT_EQ(back.secret_z85, k.secret_z85);
  EXPECT_EQ(load_public_key(dir / "hand.pub"), k.public_z85);
  EXPECT_EQ(load_public_key(dir / "hand.key"), k.public_z85);
  // The public file holds no secret.
  std::ifstream in(dir / "hand.pub");
  const std::string pub((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(pub.find(k.secret_z85), std::string::npos);
  EXPECT_THROW(write_key_files(dir.path(), "hand", k), std::runtime_error);  // no overwrite
}

TEST(KeyFiles, RefusesASecretOthersCanRead) {
  testing::TempDir dir;
  const CurveKeyPair k = generate_keypair();
  write_key_files(dir.path(), "arm", k);
  ::chmod((dir / "arm.key").c_str(), 0644);
  try {
    load_key_pair(dir / "arm.key");
    FAIL() << "loaded";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("arm.key"), std::string::npos) << what;
    EXPECT_NE(what.find("0644"), std::string::npos) << what;
    EXPECT_NE(what.find("chmod 600"), std::string::npos) << what;
    EXPECT_EQ(what.find(k.secret_z85), std::string::npos) << "the secret reached a message";
  }
}

TEST(KeyFiles, MalformedFilesNeverQuoteTheirContent) {
  testing::TempDir dir;
  const std::string almost = generate_keypair().secret_z85.substr(0, 39);
  {
    std::ofstream out(dir / "bad.key");
    out << "public: " << generate_keypair().public_z85 << "\nsecret: " << almost << "\n";
  }
  ::chmod((dir / "bad.key").c_str(), 0600);
  try {
    load_key_pair(dir / "bad.key");
    FAIL() << "loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.key"), std::string::npos);
    EXPECT_EQ(std::string(e.what()).find(almost), std::string::npos);
  }
  EXPECT_THROW(load_public_key(dir / "missing.pub"), std::runtime_error);
}

}  // namespace
}  // namespace tactile::wire
