#include "tactile/wire/sockets.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <zmq_addon.hpp>

#include "tactile/wire/envelope.hpp"

namespace tactile::wire {
namespace {

void common_options(zmq::socket_t& s) {
  s.set(zmq::sockopt::linger, 0);
}

void receiving_options(zmq::socket_t& s) {
  s.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxMessageBytes));
}

void bind_or_throw(zmq::socket_t& s, const char* kind, const std::string& endpoint) {
  try {
    s.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error(std::string("cannot bind ") + kind + " socket to '" + endpoint +
                             "': " + e.what());
  }
}

void connect_or_throw(zmq::socket_t& s, const char* kind, const std::string& endpoint) {
  try {
    s.connect(endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error(std::string("cannot connect ") + kind + " socket to '" + endpoint +
                             "': " + e.what());
  }
}

bool wait_readable(zmq::socket_t& s, std::chrono::milliseconds timeout) {
  zmq::pollitem_t item{s.handle(), 0, ZMQ_POLLIN, 0};
  try {
    return zmq::poll(&item, 1, timeout) > 0;
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return false;  // a signal: the caller checks its stop flag
    throw;
  }
}

// Receives the remaining parts of a multipart message and throws them away.
void drain(zmq::socket_ref s) {
  zmq::message_t part;
  while (s.get(zmq::sockopt::rcvmore)) {
    if (!s.recv(part, zmq::recv_flags::dontwait)) break;
  }
}

void copy_to(const zmq::message_t& m, std::vector<std::uint8_t>& out) {
  const std::span<const std::uint8_t> bytes = bytes_of(m);
  out.assign(bytes.begin(), bytes.end());
}

}  // namespace

// Not zmq::recv_multipart: it takes any number of parts through an output iterator (a
// back_inserter into a vector allocates per message), and recv_multipart_n throws on an extra
// part and leaves the rest queued. Here a message of another shape is dropped whole and counted.
bool receive_pair(zmq::socket_ref socket, zmq::message_t& first, zmq::message_t& second,
                  std::uint64_t& malformed) {
  if (!socket.recv(first, zmq::recv_flags::dontwait)) return false;
  if (!first.more()) {
    ++malformed;
    return false;
  }
  // ZeroMQ delivers a message's parts together: the second is there once the first is.
  if (!socket.recv(second, zmq::recv_flags::dontwait)) return false;
  if (second.more()) {
    drain(socket);
    ++malformed;
    return false;
  }
  return true;
}

unsigned poll_readable(std::span<zmq::socket_ref> sockets, std::chrono::milliseconds timeout,
                       int wake_fd) {
  std::array<zmq::pollitem_t, 9> items{};
  std::size_t n = std::min(sockets.size(), items.size() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    items[i].socket = sockets[i].handle();
    items[i].events = ZMQ_POLLIN;
  }
  if (wake_fd >= 0) {
    items[n].fd = wake_fd;
    items[n].events = ZMQ_POLLIN;
    ++n;
  }
  try {
    if (zmq::poll(items.data(), n, timeout) <= 0) return 0;
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return 0;
    throw;
  }
  unsigned mask = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if ((items[i].revents & ZMQ_POLLIN) != 0) mask |= 1U << i;
  }
  return mask;
}

Publisher::Publisher(zmq::context_t& ctx, const std::string& endpoint,
                     const ServerSecurity* security, int send_queue)
    : socket_(ctx, zmq::socket_type::pub) {
  common_options(socket_);
  if (security != nullptr) apply_server_security(socket_, *security);
  socket_.set(zmq::sockopt::sndhwm, send_queue);
  // Several endpoints, comma-separated: one socket bound to each (ZeroMQ's PUB sends every
  // message to the subscribers of all of them).
  std::string::size_type start = 0;
  while (true) {
    const auto comma = endpoint.find(',', start);
    bind_or_throw(socket_, "PUB", endpoint.substr(start, comma - start));
    if (!endpoints_.empty()) endpoints_ += ',';
    endpoints_ += socket_.get(zmq::sockopt::last_endpoint);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
}

void Publisher::send(std::string_view topic, std::span<const std::uint8_t> payload) {
  const std::array<zmq::const_buffer, 2> parts{zmq::buffer(topic.data(), topic.size()),
                                               zmq::buffer(payload.data(), payload.size())};
  (void)zmq::send_multipart(socket_, parts, zmq::send_flags::dontwait);
}

std::string Publisher::endpoint() const {
  return endpoints_;
}

Subscriber::Subscriber(zmq::context_t& ctx, const std::vector<std::string>& endpoints,
                       const std::vector<std::string>& topics, const ClientSecurity* security)
    : socket_(ctx, zmq::socket_type::sub) {
  common_options(socket_);
  if (security != nullptr) apply_client_security(socket_, *security);
  receiving_options(socket_);
  for (const auto& t : topics)
    socket_.set(zmq::sockopt::subscribe, t);
  for (const auto& e : endpoints)
    connect_or_throw(socket_, "SUB", e);
}

bool Subscriber::receive(TopicMessage& out, std::chrono::milliseconds timeout) {
  if (!wait_readable(socket_, timeout)) return false;
  zmq::message_t topic;
  zmq::message_t payload;
  if (!receive_pair(socket_, topic, payload, malformed_)) return false;
  out.topic.assign(static_cast<const char*>(topic.data()), topic.size());
  copy_to(payload, out.payload);
  return true;
}

Dealer::Dealer(zmq::context_t& ctx, const std::string& endpoint, const ClientSecurity* security)
    : socket_(ctx, zmq::socket_type::dealer) {
  common_options(socket_);
  if (security != nullptr) apply_client_security(socket_, *security);
  receiving_options(socket_);
  socket_.set(zmq::sockopt::sndhwm, 100);
  connect_or_throw(socket_, "DEALER", endpoint);
}

bool Dealer::send(std::span<const std::uint8_t> payload) {
  return socket_.send(zmq::buffer(payload.data(), payload.size()), zmq::send_flags::dontwait)
      .has_value();
}

bool Dealer::receive(std::vector<std::uint8_t>& payload, std::chrono::milliseconds timeout) {
  if (!wait_readable(socket_, timeout)) return false;
  zmq::message_t m;
  if (!socket_.recv(m, zmq::recv_flags::dontwait)) return false;
  if (m.more()) {
    drain(socket_);
    ++malformed_;
    return false;
  }
  copy_to(m, payload);
  return true;
}

Router::Router(zmq::context_t& ctx, const std::string& endpoint, const ServerSecurity* security)
    : socket_(ctx, zmq::socket_type::router) {
  common_options(socket_);
  if (security != nullptr) {
    if (!security->authorized_clients.empty()) {
      auth_ = std::make_unique<CurveAuthenticator>(ctx, security->authorized_clients);
    }
    apply_server_security(socket_, *security);
  }
  receiving_options(socket_);
  // Sending to a peer that is gone fails instead of vanishing silently.
  socket_.set(zmq::sockopt::router_mandatory, true);
  bind_or_throw(socket_, "ROUTER", endpoint);
}

bool Router::receive(std::string& peer, std::vector<std::uint8_t>& payload,
                     std::chrono::milliseconds timeout) {
  if (!wait_readable(socket_, timeout)) return false;
  zmq::message_t id;
  zmq::message_t m;
  if (!receive_pair(socket_, id, m, malformed_)) return false;
  peer.assign(static_cast<const char*>(id.data()), id.size());
  copy_to(m, payload);
  return true;
}

bool Router::send(const std::string& peer, std::span<const std::uint8_t> payload) {
  const std::array<zmq::const_buffer, 2> parts{zmq::buffer(peer.data(), peer.size()),
                                               zmq::buffer(payload.data(), payload.size())};
  try {
    return zmq::send_multipart(socket_, parts, zmq::send_flags::dontwait).has_value();
  } catch (const zmq::error_t& e) {
    if (e.num() == EHOSTUNREACH) return false;  // the peer is gone
    throw;
  }
}

std::string Router::endpoint() const {
  return socket_.get(zmq::sockopt::last_endpoint);
}

}  // namespace tactile::wire
