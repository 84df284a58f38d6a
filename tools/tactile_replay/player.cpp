#include "player.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <zmq_addon.hpp>

#include "tactile/util/clock.hpp"
#include "tactile/util/stop.hpp"

namespace tactile::replay {

Player::Player(zmq::context_t& ctx, const PlayerOptions& options)
    : socket_(ctx, zmq::socket_type::xpub), options_(options) {
  socket_.set(zmq::sockopt::linger, static_cast<int>(options.linger.count()));
  socket_.set(zmq::sockopt::xpub_nodrop, true);
  socket_.set(zmq::sockopt::xpub_verbose, true);
  socket_.set(zmq::sockopt::sndhwm, 10000);
  if (options.security != nullptr) wire::apply_server_security(socket_, *options.security);
  try {
    socket_.bind(options.endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("cannot bind PUB socket to '" + options.endpoint + "': " + e.what());
  }
}

std::string Player::endpoint() const {
  return socket_.get(zmq::sockopt::last_endpoint);
}

void Player::read_subscriptions(std::chrono::milliseconds timeout) {
  zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
  try {
    if (zmq::poll(&item, 1, timeout) <= 0) return;
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return;
    throw;
  }
  zmq::message_t m;
  while (socket_.recv(m, zmq::recv_flags::dontwait)) {
    // 1 + topic: subscribe; 0 + topic: unsubscribe.
    if (m.size() >= 1 && *static_cast<const std::uint8_t*>(m.data()) == 1) ++subscriptions_;
  }
}

bool Player::wait_for_subscribers() {
  const std::int64_t deadline =
      util::monotonic_ns() + std::chrono::nanoseconds(options_.wait_timeout).count();
  while (subscriptions_ < options_.wait_subscriptions) {
    if (util::stop_requested()) return false;
    const std::int64_t left = deadline - util::monotonic_ns();
    if (left <= 0) return false;
    read_subscriptions(std::chrono::milliseconds(std::clamp<std::int64_t>(left / 1000000, 1, 100)));
  }
  return true;
}

SendStatus Player::wait_until(std::int64_t deadline_ns) {
  for (;;) {
    if (util::stop_requested()) return SendStatus::kStopped;
    const std::int64_t left = deadline_ns - util::monotonic_ns();
    if (left <= 0) return SendStatus::kOk;
    read_subscriptions(std::chrono::milliseconds(std::clamp<std::int64_t>(left / 1000000, 0, 100)));
  }
}

SendStatus Player::send(std::string_view topic, std::span<const std::uint8_t> payload) {
  // The two parts go out together: once the first is accepted the second always is.
  const std::array<zmq::const_buffer, 2> parts{zmq::buffer(topic.data(), topic.size()),
                                               zmq::buffer(payload.data(), payload.size())};
  for (;;) {
    if (zmq::send_multipart(socket_, parts, zmq::send_flags::dontwait)) return SendStatus::kOk;
    if (util::stop_requested()) return SendStatus::kStopped;
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLOUT, 0};
    try {
      zmq::poll(&item, 1, std::chrono::milliseconds(100));
    } catch (const zmq::error_t& e) {
      if (e.num() != EINTR) throw;
    }
    read_subscriptions(std::chrono::milliseconds(0));
  }
}

}  // namespace tactile::replay
