#include "tactile/arm/arm_server.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "tactile/util/log.hpp"

namespace tactile::arm {
namespace {

std::int64_t checked_ns(double seconds, const char* name, bool zero_allowed) {
  if (!std::isfinite(seconds) || seconds < 0 || (seconds == 0 && !zero_allowed) || seconds > 3600) {
    throw std::invalid_argument(std::string("arm server: ") + name + " " + std::to_string(seconds) +
                                " s is not a time between 0 and 3600 s");
  }
  return static_cast<std::int64_t>(seconds * 1e9);
}

}  // namespace

ArmServer::ArmServer(zmq::context_t& ctx, ArmServerOptions options, ArmBackend& backend)
    : options_(std::move(options)),
      backend_(backend),
      router_(ctx, options_.endpoint, options_.security ? &*options_.security : nullptr),
      peer_(checked_ns(options_.deadman_s, "deadman", false)),
      heartbeat_ns_(checked_ns(options_.heartbeat_period_s, "heartbeat period", true)) {
  payload_.reserve(4096);
}

ArmServerCounters ArmServer::counters() const {
  ArmServerCounters c = counters_;
  c.garbage += router_.malformed();  // messages of another shape than [identity, payload]
  return c;
}

bool ArmServer::serve_one(std::int64_t now_ns) {
  if (!router_.receive(from_, payload_, std::chrono::milliseconds(0))) return false;
  handle(now_ns);
  return true;
}

std::size_t ArmServer::serve(std::int64_t now_ns) {
  std::size_t n = 0;
  while (serve_one(now_ns))
    ++n;
  check_deadman(now_ns);
  heartbeat_if_quiet(now_ns);
  return n;
}

void ArmServer::handle(std::int64_t now_ns) {
  const auto st = decoder_.decode(payload_);
  const v1::Envelope& env = decoder_.envelope();
  if (st != wire::DecodeStatus::kOk) {
    ++counters_.garbage;
    return;
  }
  if (env.has_heartbeat()) {
    const ArmPeer::Heard h = peer_.heartbeat(from_, now_ns);
    if (!h.accepted) {
      ++counters_.strangers;  // another client's heartbeat while ours is alive: refused
      return;
    }
    if (h.connected) util::log_info("hand_node connected");
    // The old client fell silent and the arm is held: a new one (a restarted hand_node) takes
    // over.
    if (h.new_client) util::log_info("a new client takes over after the deadman hold");
    return;
  }
  if (!env.has_arm_command()) {
    ++counters_.garbage;
    return;
  }
  if (wire::read_arm_command(env.arm_command(), options_.fingertip_ids, command_) !=
      wire::DecodeStatus::kOk) {
    ++counters_.invalid_commands;
    return;
  }
  const ArmPeer::Heard h = peer_.command(from_, now_ns);
  if (h.connected) util::log_info("hand_node connected");
  if (h.new_client) util::log_warn("commands now come from another client");
  if (h.resumed) util::log_info("hand_node commands again after the deadman hold");
  ++counters_.commands;
  last_command_ = command_.sequence;
  if (!backend_.write(command_, now_ns)) ++counters_.invalid_commands;
}

// Checked whenever the caller serves the socket, not only when it sends a state: with states at
// 30 Hz a check per state would hold the arm up to a period late.
void ArmServer::check_deadman(std::int64_t now_ns) {
  if (!peer_.deadman_trips(now_ns)) return;
  ++counters_.deadman_trips;
  backend_.hold(now_ns);
  util::log_warn("deadman: nothing from hand_node for {:.0f} ms: arm held",
                 static_cast<double>(now_ns - peer_.last_heard_ns()) * 1e-6);
}

void ArmServer::send_envelope(v1::Envelope& env, std::int64_t now_ns) {
  wire::encode(env, out_);
  // False: the peer is gone or its queue is full. Its silence trips the deadman; nothing to do.
  (void)router_.send(peer_.peer(), wire::bytes_of(out_));
  last_sent_ns_ = now_ns;
}

bool ArmServer::send_state(std::int64_t now_ns) {
  if (!peer_.has_peer()) return false;
  wire::ArmStateData s = backend_.read(now_ns);
  if (s.time_ns == 0) s.time_ns = now_ns;
  s.last_command_sequence = last_command_;
  s.deadman = peer_.report_deadman();
  wire::fill_arm_state(s, options_.fingertip_ids, *state_env_.mutable_arm_state());
  send_envelope(state_env_, now_ns);
  ++counters_.states_sent;
  check_deadman(now_ns);
  return true;
}

void ArmServer::heartbeat_if_quiet(std::int64_t now_ns) {
  if (heartbeat_ns_ == 0 || !peer_.has_peer() || now_ns - last_sent_ns_ < heartbeat_ns_) return;
  v1::Heartbeat& hb = *heartbeat_env_.mutable_heartbeat();
  hb.set_time_ns(now_ns);
  if (hb.sender().empty()) hb.set_sender("arm_server");
  send_envelope(heartbeat_env_, now_ns);
  ++counters_.heartbeats_sent;
}

}  // namespace tactile::arm
