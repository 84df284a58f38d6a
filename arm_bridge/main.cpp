// arm_bridge: an arm controller endpoint for hand_node on arm::ArmServer (docs/arm.md). With the
// built-in kinematic arm it brings hand_node up before a real arm is connected; backend.cpp is
// where a lab's arm goes.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>

#include "backend.hpp"
#include "tactile/arm/arm_server.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/security.hpp"
#include "tactile/wire/sockets.hpp"

namespace {

using tactile::arm::ArmServer;
using tactile::arm::ArmServerOptions;

struct Options {
  ArmServerOptions server;
  tactile::arm_bridge::BackendOptions backend;
  std::string key;
  std::vector<std::string> clients;
  std::vector<double> start{0.35, -0.10, 0.25, 0.0};
  std::vector<std::string> fingertips{"left", "right"};
  double state_rate_hz = 100.0;
};

// Serves until a stop: messages as they come, the deadman at least every 5 ms, an ArmState at
// the state rate.
int serve(const Options& opt) {
  ArmServerOptions so = opt.server;
  if (!opt.key.empty()) {
    tactile::wire::ServerSecurity sec{tactile::wire::load_key_pair(opt.key), {}};
    for (const std::string& c : opt.clients)
      sec.authorized_clients.push_back(tactile::wire::load_public_key(c));
    so.security = std::move(sec);
  } else if (!opt.clients.empty()) {
    throw tactile::cli::UsageError("--client needs --key");
  }
  so.fingertip_ids = {opt.fingertips[0], opt.fingertips[1]};
  tactile::arm_bridge::BackendOptions bo = opt.backend;
  bo.kinematic.start = {{opt.start[0], opt.start[1], opt.start[2]}, opt.start[3]};

  tactile::util::install_stop_handlers();
  tactile::wire::install_protobuf_log_handler();
  zmq::context_t ctx;
  const std::unique_ptr<tactile::arm::ArmBackend> backend =
      tactile::arm_bridge::make_backend(bo, tactile::util::realtime_ns());
  ArmServer server(ctx, so, *backend);
  tactile::util::log_info(
      "arm controller on {}{}, deadman {:.0f} ms, ArmState at {:g} Hz, fingertips {} and {}",
      server.endpoint(), so.security ? " (CURVE)" : "", so.deadman_s * 1e3, opt.state_rate_hz,
      opt.fingertips[0], opt.fingertips[1]);
  const auto period_ns = static_cast<std::int64_t>(1e9 / opt.state_rate_hz);
  std::int64_t next_state_ns = tactile::util::realtime_ns() + period_ns;
  std::array<zmq::socket_ref, 1> sockets{server.socket()};
  while (!tactile::util::stop_requested()) {
    const std::int64_t wait_ns = next_state_ns - tactile::util::realtime_ns();
    tactile::wire::poll_readable(
        sockets, std::chrono::milliseconds(std::clamp<std::int64_t>(wait_ns / 1'000'000, 0, 5)));
    server.serve(tactile::util::realtime_ns());
    const std::int64_t now = tactile::util::realtime_ns();
    if (now >= next_state_ns) {
      server.send_state(now);
      next_state_ns = std::max(next_state_ns + period_ns, now);
    }
  }
  // On the way out the arm stops where it is: nobody commands it any more.
  backend->hold(tactile::util::realtime_ns());
  const tactile::arm::ArmServerCounters c = server.counters();
  tactile::util::log_info(
      "stopped: arm held; commands {} (refused {}: garbage {}, strangers {}, invalid {}), "
      "deadman trips {}, states sent {}, clients refused by CURVE {}",
      c.commands, c.refused(), c.garbage, c.strangers, c.invalid_commands, c.deadman_trips,
      c.states_sent, server.refused_clients());
  return 0;
}

int run(int argc, char** argv) {
  Options opt;
  std::string log_level = "info";
  CLI::App app{
      "arm_bridge: the arm controller's end of the arm link (ArmCommand/ArmState, docs/arm.md) "
      "on arm::ArmServer, with a built-in kinematic arm that follows every command exactly (no "
      "physics). For bringing hand_node up before the real arm is connected; a lab's arm goes "
      "in arm_bridge/backend.cpp."};
  app.add_option("--endpoint", opt.server.endpoint, "ROUTER endpoint to bind")
      ->capture_default_str();
  app.add_option("--key", opt.key,
                 "CURVE: the arm controller's key pair (NAME.key, tactile_keygen)");
  app.add_option("--client", opt.clients,
                 "with --key, a client public key (NAME.pub) let in (repeatable; none: any "
                 "client that knows the arm's public key)");
  app.add_option("--deadman", opt.server.deadman_s,
                 "hold the arm after this long without a word from hand_node (s)")
      ->check(CLI::Range(0.001, 3600.0))
      ->capture_default_str();
  app.add_option("--heartbeat", opt.server.heartbeat_period_s,
                 "a Heartbeat to hand_node when nothing went to it this long (s); 0: never")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option("--state-rate", opt.state_rate_hz, "ArmStates a second")
      ->check(CLI::Range(0.1, 10000.0))
      ->capture_default_str();
  app.add_option("--fingertips", opt.fingertips,
                 "the sensor ids of fingertip 0 and 1, as hand_node's configuration names them")
      ->expected(2)
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--start", opt.start, "kinematic arm: the wrist's start pose x,y,z (m),yaw (rad)")
      ->expected(4)
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--finger-open", opt.backend.kinematic.finger_open_m,
                 "kinematic arm: each fingertip's distance from the grasp centre at the start (m)")
      ->check(CLI::Range(0.0, 0.06))
      ->capture_default_str();
  tactile::cli::add_log_level(app, log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    tactile::util::set_log_level(tactile::util::parse_log_level(log_level));
    return serve(opt);
  });
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("arm_bridge");
  return run(argc, argv);
}
