// hand_node: subscribes to the fingertips' TactileFrames, runs the flags, the finger speed
// estimator and the grasp-move-twist sequencers, and commands the arm controller.
#include <CLI/CLI.hpp>

#include "src/hand_config.hpp"
#include "src/hand_node.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/control/config.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/realtime.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"

namespace {

int run(int argc, char** argv) {
  std::string config_path;
  std::vector<std::string> subscribe;
  std::string arm;
  std::string events;
  std::string log_level = "info";
  CLI::App app{
      "hand_node: the hand PC of the tactile slippage control system. Subscribes to "
      "TactileFrames, raises SEARCH/MOVE/TOUCH/SLIP/OVER, estimates finger speeds with "
      "re-compression on slip, runs grasp-move-release and grasp-twist, and sends "
      "ArmCommands to the arm controller."};
  app.add_option("--config", config_path, "configuration file (tactile-hand/1 YAML)")->required();
  app.add_option("--subscribe", subscribe,
                 "sensor_node endpoint to subscribe to (repeatable; replaces the file's list)")
      ->allow_extra_args(false)
      ->check(tactile::cli::non_empty());
  app.add_option("--arm", arm,
                 "arm controller endpoint (default tcp://127.0.0.1:5556 or the file's)")
      ->check(tactile::cli::non_empty());
  const CLI::Option* events_opt = app.add_option(
      "--events", events,
      "publish events on this endpoint (e.g. tcp://*:5558; several comma-separated); \"\" "
      "publishes none, whatever the file says");
  tactile::cli::add_log_level(app, log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    tactile::util::set_log_level(tactile::util::parse_log_level(log_level));
    std::vector<std::string> warnings;
    tactile::hand::HandConfig cfg = tactile::hand::load_hand_config(config_path, &warnings);
    for (const auto& w : warnings)
      tactile::util::log_warn("{}", w);
    if (!subscribe.empty()) cfg.subscribe = subscribe;
    if (!arm.empty()) cfg.arm = arm;
    tactile::cli::override_if_given(events_opt, events, cfg.events);
    tactile::util::log_info("{}", tactile::control::describe_controller(cfg.controller));
    // Before any thread exists, so that ZeroMQ's threads inherit it.
    tactile::util::apply_realtime_scheduling(cfg.realtime, config_path + ": realtime");
    if (cfg.realtime.priority != 0 || cfg.realtime.lock_memory)
      tactile::util::log_info("real-time scheduling: {}", tactile::util::describe(cfg.realtime));
    tactile::util::install_stop_handlers();
    tactile::wire::install_protobuf_log_handler();
    zmq::context_t ctx;
    tactile::hand::HandNode node(std::move(cfg), ctx);
    switch (node.run()) {
      case tactile::hand::Outcome::kDone:
        tactile::util::log_info("task done");
        return 0;
      case tactile::hand::Outcome::kStopped:
        return 0;
      case tactile::hand::Outcome::kAborted:
        tactile::util::log_error("task aborted");
        return 3;
      case tactile::hand::Outcome::kArmLost:  // HandNode said why, in one line
        return 4;
    }
    return 0;
  });
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("hand_node");
  return run(argc, argv);
}
