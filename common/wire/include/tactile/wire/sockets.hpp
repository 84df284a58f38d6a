#pragma once

// Thin ZeroMQ endpoints: they only move bytes. Would-block and timeouts are values (false);
// real failures (a bad endpoint, a port in use) throw std::runtime_error naming the endpoint.
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "tactile/wire/security.hpp"

namespace tactile::wire {

// Waits up to `timeout` until at least one of the sockets (the first 8) has a message; returns a
// bit mask (bit i: sockets[i] is readable), 0 on timeout or when a signal interrupted the wait.
// With `wake_fd` (a file descriptor, such as a timerfd for a wake-up finer than the millisecond
// timeout), the wait also ends when it is readable: the bit after the sockets' bits.
unsigned poll_readable(std::span<zmq::socket_ref> sockets, std::chrono::milliseconds timeout,
                       int wake_fd = -1);

// The bytes of a received message part: bytes_of in envelope.hpp, for ZeroMQ's messages.
inline std::span<const std::uint8_t> bytes_of(const zmq::message_t& m) noexcept {
  return {m.data<std::uint8_t>(), m.size()};
}

// Takes one queued [first, second] message without waiting, into the caller's messages (reused
// from call to call). False when nothing is queued, and when the message has another shape: then
// all its parts are dropped and counted in `malformed`. Never throws for a message's shape.
bool receive_pair(zmq::socket_ref socket, zmq::message_t& first, zmq::message_t& second,
                  std::uint64_t& malformed);

// ZeroMQ's own default high-water mark, in messages.
inline constexpr int kDefaultSendQueue = 1000;

// PUB side of a tactile, event or ground-truth stream (topics: envelope.hpp).
class Publisher {
 public:
  // With `security`, a CURVE server: only subscribers that know its public key receive.
  // `send_queue`: messages kept for each subscriber that falls behind (ZeroMQ's SNDHWM); past it
  // that subscriber's messages are dropped. `endpoint` may name several, comma-separated (e.g.
  // "tcp://*:5555,ipc:///tmp/run/sensor.ipc"): it binds each, and every message goes to the
  // subscribers of all of them.
  Publisher(zmq::context_t& ctx, const std::string& endpoint,
            const ServerSecurity* security = nullptr, int send_queue = kDefaultSendQueue);
  // Sends [topic, payload]. Never blocks: past the high-water mark a PUB socket drops.
  void send(std::string_view topic, std::span<const std::uint8_t> payload);
  // The endpoints actually bound (a wildcard port resolved), comma-separated as given, e.g.
  // "tcp://0.0.0.0:5555".
  std::string endpoint() const;

 private:
  zmq::socket_t socket_;
  std::string endpoints_;
};

struct TopicMessage {
  std::string topic;
  std::vector<std::uint8_t> payload;  // capacity reused from message to message
};

// SUB side: connects to one or more publishers and subscribes to topic prefixes.
class Subscriber {
 public:
  // With `security`, a CURVE client: it accepts data only from publishers holding the secret
  // key of `security->server_public_z85`.
  Subscriber(zmq::context_t& ctx, const std::vector<std::string>& endpoints,
             const std::vector<std::string>& topics, const ClientSecurity* security = nullptr);
  // Waits up to `timeout` for one [topic, payload] message. A message of another shape is
  // dropped and counted (malformed()). Messages larger than kMaxMessageBytes never arrive.
  bool receive(TopicMessage& out, std::chrono::milliseconds timeout);
  std::uint64_t malformed() const { return malformed_; }
  zmq::socket_ref socket() { return socket_; }

 private:
  zmq::socket_t socket_;
  std::uint64_t malformed_ = 0;
};

// hand_node's side of the arm link.
class Dealer {
 public:
  Dealer(zmq::context_t& ctx, const std::string& endpoint,
         const ClientSecurity* security = nullptr);
  // False when it would block (the arm controller is absent and the queue is full).
  bool send(std::span<const std::uint8_t> payload);
  bool receive(std::vector<std::uint8_t>& payload, std::chrono::milliseconds timeout);
  std::uint64_t malformed() const { return malformed_; }
  zmq::socket_ref socket() { return socket_; }

 private:
  zmq::socket_t socket_;
  std::uint64_t malformed_ = 0;
};

// The arm controller's side of the arm link.
class Router {
 public:
  // With `security`, a CURVE server that lets in only the authorized client keys (it runs the
  // context's authenticator: one secured Router per context).
  Router(zmq::context_t& ctx, const std::string& endpoint,
         const ServerSecurity* security = nullptr);
  // Clients refused by the authenticator (0 without security).
  std::uint64_t refused_clients() const { return auth_ ? auth_->refused() : 0; }
  // Receives one message and the identity of the peer that sent it.
  bool receive(std::string& peer, std::vector<std::uint8_t>& payload,
               std::chrono::milliseconds timeout);
  // False when the peer is unknown (gone) or it would block.
  bool send(const std::string& peer, std::span<const std::uint8_t> payload);
  std::string endpoint() const;
  std::uint64_t malformed() const { return malformed_; }
  zmq::socket_ref socket() { return socket_; }

 private:
  std::unique_ptr<CurveAuthenticator> auth_;
  zmq::socket_t socket_;
  std::uint64_t malformed_ = 0;
};

}  // namespace tactile::wire
