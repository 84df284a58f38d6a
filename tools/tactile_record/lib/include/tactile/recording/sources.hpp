#pragma once

// The subscriptions of tactile_record and tactile_live: one SUB socket per publisher, so every
// message is known by the endpoint it came from, each plain or CURVE (docs/security.md).
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>
#include <zmq.hpp>

#include "tactile/v1/log.pb.h"
#include "tactile/wire/security.hpp"

namespace tactile::recording {

struct CurveSource {
  std::string endpoint;
  std::filesystem::path server_public_key;  // the publisher's NAME.pub (or its NAME.key)
};

// Parses "ENDPOINT=FILE"; throws std::invalid_argument naming the text.
CurveSource parse_curve_source(const std::string& text);

struct SourceOptions {
  std::vector<std::string> endpoints;  // plain connections
  std::vector<CurveSource> curve;      // CURVE connections
  // This program's own key pair for CURVE (a .key file); empty: a fresh pair for this run
  // (publishers admit any client that knows their public key).
  std::filesystem::path client_key;
  std::vector<std::string> topics;  // prefixes subscribed on every source
  std::int64_t max_message_bytes = std::int64_t{64} << 20;
  int receive_hwm = 100000;  // messages queued per source before ZeroMQ drops
};

class Sources {
 public:
  struct Message {
    zmq::message_t topic;
    zmq::message_t payload;
    std::size_t source = 0;  // index of the endpoint
  };

  // Connects to every endpoint. Throws std::invalid_argument / std::runtime_error naming the
  // endpoint or key file that is wrong.
  Sources(zmq::context_t& ctx, const SourceOptions& options);

  // Waits up to `timeout` for the next [topic, payload] message of any source, taking the
  // sources in turn. False on timeout or when a signal interrupted the wait. A message of another
  // shape is dropped and counted (malformed()). Never allocates beyond ZeroMQ's own buffers.
  bool receive(Message& out, std::chrono::milliseconds timeout);

  std::size_t size() const { return sockets_.size(); }
  const std::string& endpoint(std::size_t i) const { return endpoints_[i]; }
  bool curve(std::size_t i) const { return curve_[i]; }
  const std::vector<std::string>& topics() const { return topics_; }
  std::uint64_t malformed() const { return malformed_; }
  // The endpoints nothing at all (not even a malformed message) has come from yet, joined with
  // ", "; empty once every source was heard. What a recorder or viewer names when it gives up
  // on a silent publisher (--silence-timeout, docs/tools.md).
  std::string unheard() const;
  // For the log header.
  std::vector<v1::LogSource> describe() const;

 private:
  bool try_receive(std::size_t i, Message& out);

  std::vector<zmq::socket_t> sockets_;
  std::vector<std::string> endpoints_;
  std::vector<bool> curve_;
  std::vector<bool> heard_;
  std::vector<std::string> topics_;
  std::vector<zmq::pollitem_t> items_;
  std::size_t next_ = 0;
  std::uint64_t malformed_ = 0;
};

}  // namespace tactile::recording
