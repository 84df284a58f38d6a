#pragma once

// tactile_replay's publisher: plays a log's messages back on an XPUB socket, byte for byte, at
// the recorded pace (scaled) or as fast as the subscribers take them.
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "tactile/wire/security.hpp"

namespace tactile::replay {

struct PlayerOptions {
  std::string endpoint = "tcp://*:5555";
  const wire::ServerSecurity* security = nullptr;
  // Start only once this many subscriptions (one per topic prefix a subscriber asks for) arrived.
  int wait_subscriptions = 0;
  std::chrono::milliseconds wait_timeout{10000};
  // Linger at the end so queued messages still reach slow subscribers.
  std::chrono::milliseconds linger{5000};
};

enum class SendStatus : std::uint8_t { kOk, kStopped };

class Player {
 public:
  // Binds; throws std::runtime_error naming the endpoint.
  Player(zmq::context_t& ctx, const PlayerOptions& options);

  // Blocks until the wanted subscriptions arrived; false on timeout or stop request.
  bool wait_for_subscribers();
  // Sends [topic, payload]. Never drops: when a subscriber's queue is full it waits (checking
  // for a stop request) until there is room.
  SendStatus send(std::string_view topic, std::span<const std::uint8_t> payload);
  // Waits until the monotonic time `deadline_ns`, answering subscriptions meanwhile; kStopped on
  // a stop request.
  SendStatus wait_until(std::int64_t deadline_ns);

  std::string endpoint() const;
  int subscriptions() const { return subscriptions_; }

 private:
  void read_subscriptions(std::chrono::milliseconds timeout);

  zmq::socket_t socket_;
  PlayerOptions options_;
  int subscriptions_ = 0;
};

}  // namespace tactile::replay
