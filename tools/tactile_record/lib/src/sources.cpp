#include "tactile/recording/sources.hpp"

#include <algorithm>
#include <stdexcept>

#include "tactile/wire/sockets.hpp"

namespace tactile::recording {

CurveSource parse_curve_source(const std::string& text) {
  const auto eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size()) {
    throw std::invalid_argument("'" + text + "' is not ENDPOINT=PUBLIC_KEY_FILE");
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

Sources::Sources(zmq::context_t& ctx, const SourceOptions& o) : topics_(o.topics) {
  if (o.endpoints.empty() && o.curve.empty()) throw std::invalid_argument("no endpoint given");
  if (o.topics.empty()) throw std::invalid_argument("no topic given");
  wire::CurveKeyPair client;
  if (!o.curve.empty()) {
    if (!wire::curve_available()) {
      throw std::runtime_error("this libzmq has no CURVE support, needed for " +
                               o.curve.front().endpoint);
    }
    client = o.client_key.empty() ? wire::generate_keypair() : wire::load_key_pair(o.client_key);
  }
  auto add = [&](const std::string& endpoint, const wire::ClientSecurity* security) {
    // Named twice, an endpoint would be subscribed twice: a plain subscription to a CURVE
    // publisher hears nothing (and a silence timeout then names it), a second CURVE one records
    // every message twice.
    if (std::find(endpoints_.begin(), endpoints_.end(), endpoint) != endpoints_.end()) {
      throw std::invalid_argument("'" + endpoint +
                                  "' is given twice; name each publisher once (with --curve "
                                  "ENDPOINT=KEY alone when it uses CURVE)");
    }
    zmq::socket_t s(ctx, zmq::socket_type::sub);
    s.set(zmq::sockopt::linger, 0);
    s.set(zmq::sockopt::rcvhwm, o.receive_hwm);
    s.set(zmq::sockopt::maxmsgsize, o.max_message_bytes);
    if (security != nullptr) wire::apply_client_security(s, *security);
    for (const auto& t : o.topics)
      s.set(zmq::sockopt::subscribe, t);
    try {
      s.connect(endpoint);
    } catch (const zmq::error_t& e) {
      throw std::invalid_argument("cannot connect to '" + endpoint + "': " + e.what());
    }
    sockets_.push_back(std::move(s));
    endpoints_.push_back(endpoint);
    curve_.push_back(security != nullptr);
    heard_.push_back(false);
  };
  for (const auto& e : o.endpoints)
    add(e, nullptr);
  for (const auto& c : o.curve) {
    wire::ClientSecurity sec;
    sec.keys = client;
    sec.server_public_z85 = wire::load_public_key(c.server_public_key);
    add(c.endpoint, &sec);
  }
  for (auto& s : sockets_)
    items_.push_back(zmq::pollitem_t{s.handle(), 0, ZMQ_POLLIN, 0});
}

bool Sources::try_receive(std::size_t i, Message& out) {
  const std::uint64_t malformed_before = malformed_;
  const bool ok = wire::receive_pair(sockets_[i], out.topic, out.payload, malformed_);
  if (ok || malformed_ != malformed_before) heard_[i] = true;
  if (!ok) return false;
  out.source = i;
  return true;
}

std::string Sources::unheard() const {
  std::string s;
  for (std::size_t i = 0; i < endpoints_.size(); ++i) {
    if (heard_[i]) continue;
    if (!s.empty()) s += ", ";
    s += endpoints_[i];
  }
  return s;
}

bool Sources::receive(Message& out, std::chrono::milliseconds timeout) {
  const std::size_t n = sockets_.size();
  for (int round = 0; round < 2; ++round) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = (next_ + k) % n;
      if (try_receive(i, out)) {
        next_ = (i + 1) % n;
        return true;
      }
    }
    if (round == 1) break;
    try {
      if (zmq::poll(items_.data(), items_.size(), timeout) <= 0) return false;
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR) return false;
      throw;
    }
  }
  return false;
}

std::vector<v1::LogSource> Sources::describe() const {
  std::vector<v1::LogSource> out;
  for (std::size_t i = 0; i < sockets_.size(); ++i) {
    v1::LogSource s;
    s.set_endpoint(endpoints_[i]);
    for (const auto& t : topics_)
      s.add_topics(t);
    s.set_curve(curve_[i]);
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace tactile::recording
