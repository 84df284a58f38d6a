// rig: the simulated rig (docs/rig.md). `rig --lockstep --scenario FILE --report FILE.json` runs
// the scenario in one process on simulated time; `rig --scenario FILE` runs it in real time with
// fake GigE Vision cameras and the arm controller, for sensor_node and hand_node.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "tactile/cli/run.hpp"
#include "tactile/control/config.hpp"
#include "tactile/rig/control_link.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/plots.hpp"
#include "tactile/rig/realtime.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/rig/sweep.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/security.hpp"

namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "rig: the simulated rig of the tactile slippage control system (docs/rig.md).\n"
      "  rig --lockstep --scenario FILE --report FILE.json [--plots DIR]\n"
      "runs the grasp-move-twist scenario in one process on simulated time, with the real\n"
      "measurement and control cores in the loop; the same seed gives the same report.\n"
      "  rig --scenario FILE [--report FILE.json] [--plots DIR]\n"
      "runs it in real time: one fake GigE Vision camera per fingertip (127.0.0.2, 127.0.0.3),\n"
      "the arm controller (ROUTER, tcp://*:5556, with a deadman) and ground truth (tcp://*:5557),\n"
      "for sensor_node and hand_node; the report scores what they measured and decided.\n"
      "  rig --scenario FILE --write-configs DIR\n"
      "writes the sensors' calibrations and the configurations of sensor_node and hand_node for "
      "it.\n"
      "  rig --sweep N --seed S --out DIR [--jobs J] [--shard K/N] [--resume] [--calibration "
      "FILE]\n"
      "draws N random scenarios, runs each in lockstep in a child rig process and writes\n"
      "DIR/sweep.csv, summary.md and sweep.png (docs/slip.md).\n"
      "  rig --sweep-merge DIR... --out DIR\n"
      "combines the shards of one sweep into one table and plot."};
  std::string scenario_path;
  std::string report_path;
  std::string plots_dir;
  std::string timing_path;
  std::string series_path;
  std::string calibration_dir;
  bool lockstep = false;
  double dt_s = 0;
  std::string log_level = "info";
  app.add_option("--scenario", scenario_path,
                 "scenario file (tactile-scenario/1); required except for --sweep, --sweep-merge");
  app.add_option("--report", report_path, "write the scenario report (JSON) here");
  app.add_flag("--lockstep", lockstep, "simulated time in one process, deterministic");
  app.add_option("--plots", plots_dir, "write the run's plots (PNG) into this directory");
  app.add_option("--timing", timing_path, "write the wall-clock and CPU timing (JSON) here");
  app.add_option("--series", series_path,
                 "write the per-frame series (CSV) here, and beside it the element-frames where "
                 "measured and true slip disagree");
  app.add_option("--calibration-dir", calibration_dir,
                 "write the simulated sensors' calibration files (left.yaml, right.yaml) here");
  app.add_option("--dt", dt_s, "physics step (s), overriding the scenario's")
      ->check(CLI::Range(1e-7, 1e-3));
  tactile::cli::add_log_level(app, log_level);
  tactile::rig::RealtimeOptions rt;
  std::vector<std::string> cameras;
  std::string write_configs;
  std::vector<std::string> observe_frames;
  app.add_option(
         "--cameras", cameras,
         "real time: the two cameras' IPv4 addresses, left,right (default 127.0.0.2,127.0.0.3)")
      ->delimiter(',')
      ->check(tactile::cli::non_empty());
  app.add_option("--camera-netns", rt.camera_netns,
                 "real time: serve the cameras inside this network namespace (a name `ip netns "
                 "add` made, or a path such as /proc/PID/ns/net): behind a link of their own, "
                 "which scripts/run-system shapes to line rate; root");
  app.add_option("--camera-packet-size", rt.camera_packet_size,
                 "--write-configs: the GVSP packet size sensor_node asks of the cameras (at most "
                 "the camera link's MTU; default: sensor_node's)")
      ->check(CLI::Range(576, 65500));
  app.add_option("--arm", rt.arm_endpoint, "real time: the arm controller's endpoint")
      ->capture_default_str();
  app.add_option("--truth", rt.truth_endpoint,
                 "real time: ground-truth PUB endpoint (several comma-separated; empty: none)")
      ->capture_default_str();
  app.add_option(
         "--observe-frames", observe_frames,
         "real time: sensor_node endpoint to score (repeatable; default tcp://127.0.0.1:5555)")
      ->allow_extra_args(false)
      ->check(tactile::cli::non_empty());
  app.add_option("--observe-events", rt.observe_events, "real time: hand_node's event endpoint")
      ->capture_default_str();
  app.add_option("--deadman", rt.deadman_s,
                 "real time: hold the arm after this long without hand_node (s)")
      ->capture_default_str()
      ->check(CLI::Range(0.005, 10.0));
  app.add_option(
         "--late-every", rt.late_every,
         "real time, for tests: leave every Nth frame unrendered, as if the rig ran late, "
         "so the cameras send the image before it again (the truth's resend path; 0: never)")
      ->capture_default_str();
  app.add_option("--wait-for-hand", rt.wait_for_hand_s,
                 "real time: give up when no hand_node speaks within this (s)")
      ->capture_default_str();
  app.add_flag("--full-noise", rt.full_noise,
               "real time: fresh noise on every pixel of every frame, not only the element disks");
  std::string arm_key;
  std::vector<std::string> arm_clients;
  std::string observe_key;
  std::string ready_path;
  app.add_option("--ready-file", ready_path,
                 "real time: write this file once the cameras serve and the arm controller "
                 "listens, and remove it on exit (a health check, docker/compose.yaml)");
  app.add_option("--arm-key", arm_key,
                 "real time: CURVE on the arm link: the arm controller's key pair (NAME.key, "
                 "docs/security.md)");
  app.add_option("--arm-client", arm_clients,
                 "real time: with --arm-key, a client public key (NAME.pub) let in (repeatable; "
                 "none: any client that knows the arm's public key)")
      ->allow_extra_args(false);
  app.add_option("--observe-key", observe_key,
                 "real time: sensor_node's public key (NAME.pub), for its CURVE-secured frames");
  std::string observe_events_key;
  app.add_option("--observe-events-key", observe_events_key,
                 "real time: hand_node's public key (NAME.pub), for its CURVE-secured events");
  std::string truth_key;
  app.add_option("--truth-key", truth_key,
                 "real time: CURVE on the ground-truth PUB: its key pair (NAME.key); a subscriber "
                 "needs NAME.pub");
  app.add_option("--write-configs", write_configs,
                 "write left.yaml, right.yaml, sensor_node.yaml and hand_node.yaml for this "
                 "scenario into DIR and exit");
  tactile::rig::sweep::SweepOptions sweep;
  std::string shard;
  std::vector<std::string> merge_dirs;
  auto* sweep_opt =
      app.add_option("--sweep", sweep.scenarios,
                     "draw this many random scenarios and run each in lockstep (docs/slip.md)")
          ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{10000000}));
  auto* merge_opt = app.add_option("--sweep-merge", merge_dirs,
                                   "combine these sweep directories (shards of one sweep)")
                        ->allow_extra_args(true)
                        ->excludes(sweep_opt);
  std::string slip_detector;
  app.add_option(
         "--slip-detector", slip_detector,
         "the controller's slip detector, paper, field or learned, overriding the scenario's "
         "controller.slip_detector (docs/slip.md)")
      ->check(tactile::cli::non_empty());
  std::string sensor;
  app.add_option("--sensor", sensor,
                 "sweep: the sensor of every scenario, rig (the rig's Gaussian spot), feelers "
                 "(the paper's feeler element) or drawn (one drawn per scenario: element, "
                 "stiffness, spot, shot noise, calibration error) (docs/slip.md)")
      ->needs(sweep_opt);
  std::string lab_calibration;
  app.add_option("--calibration", lab_calibration,
                 "sweep: a lab's calibration file (tactile-calibration/1) every scenario renders: "
                 "its layout, curves, thresholds and image (docs/slip.md, \"Retraining for your "
                 "own sensor\")")
      ->needs(sweep_opt);
  std::string grip;
  app.add_option("--grip", grip,
                 "the controller's grip, paper or margin, overriding the scenario's "
                 "controller.grip; with --sweep, every run's (docs/control.md)")
      ->check(tactile::cli::non_empty());
  app.add_option("--detectors", sweep.detectors,
                 "sweep: run every scenario once with each of these slip detectors, separated by "
                 "commas")
      ->delimiter(',')
      ->default_str("paper,field,learned");
  app.add_option("--seed", sweep.seed, "sweep: the draw's seed")->capture_default_str();
  app.add_option("--out", sweep.out, "sweep, sweep-merge: the output directory");
  app.add_option("--jobs", sweep.jobs, "sweep: child processes at a time (default: the cores)")
      ->check(CLI::Range(1, 1024));
  app.add_option("--shard", shard, "sweep: run only part K of N of the draw, as K/N");
  app.add_flag("--resume", sweep.resume,
               "sweep: keep the runs whose reports --out holds from an earlier run of the same "
               "sweep (cut short by a signal or a kill) and run only the others")
      ->needs(sweep_opt);
  app.add_option("--max-sim-time", sweep.max_sim_time_s,
                 "sweep: cut each scenario at this much simulated time (s; short test sweeps)")
      ->check(CLI::Range(0.1, 3600.0));
  return tactile::cli::run(app, argc, argv, [&] {
    try {
      tactile::util::set_log_level(tactile::util::parse_log_level(log_level));
    } catch (const std::invalid_argument& e) {
      throw tactile::cli::UsageError(std::string("--log-level: ") + e.what());
    }
    if (!grip.empty() && !tactile::control::grip_from_string(grip)) {
      throw tactile::cli::UsageError("--grip must be " + std::string(tactile::control::kGripNames) +
                                     "; got '" + grip + "'");
    }
    if (*sweep_opt || *merge_opt) {
      if (sweep.out.empty())
        throw tactile::cli::UsageError("--sweep and --sweep-merge need --out DIR");
      if (!scenario_path.empty() || lockstep)
        throw tactile::cli::UsageError(
            "--sweep and --sweep-merge take no --scenario or --lockstep");
      if (*merge_opt) {
        tactile::rig::sweep::merge_sweeps({merge_dirs.begin(), merge_dirs.end()}, sweep.out);
        return 0;
      }
      if (!shard.empty()) {
        try {
          const tactile::rig::sweep::Shard k = tactile::rig::sweep::parse_shard(shard);
          sweep.shard = k.shard;
          sweep.shards = k.shards;
        } catch (const std::invalid_argument& e) {
          throw tactile::cli::UsageError(std::string("--shard: ") + e.what());
        }
      }
      if (!slip_detector.empty())
        throw tactile::cli::UsageError("--sweep takes --detectors, not --slip-detector");
      for (auto it = sweep.detectors.begin(); it != sweep.detectors.end(); ++it) {
        if (!tactile::control::slip_detector_from_string(*it) ||
            std::find(sweep.detectors.begin(), it, *it) != it) {
          throw tactile::cli::UsageError("--detectors must list detectors (" +
                                         std::string(tactile::control::kSlipDetectorNames) +
                                         "), each once, separated by commas; got '" +
                                         fmt::format("{}", fmt::join(sweep.detectors, ",")) + "'");
        }
      }
      sweep.grip = grip;
      if (!sensor.empty()) {
        const auto set = tactile::rig::sweep::sensor_set_from_string(sensor);
        if (!set) {
          throw tactile::cli::UsageError("--sensor must be " +
                                         std::string(tactile::rig::sweep::kSensorSetNames) +
                                         "; got '" + sensor + "'");
        }
        sweep.sensor = *set;
      }
      // Refused now, naming the file, not in every child.
      if (!lab_calibration.empty())
        sweep.lab_sensor = tactile::rig::load_lab_sensor(lab_calibration);
      tactile::util::install_stop_handlers();
      tactile::rig::sweep::run_sweep(sweep);
      // Cut short by a signal: the partial table is written, and the status says it is partial.
      return tactile::util::interrupted_exit_status();
    }
    if (scenario_path.empty()) throw tactile::cli::UsageError("--scenario is required");
    if (!slip_detector.empty() && !tactile::control::slip_detector_from_string(slip_detector)) {
      throw tactile::cli::UsageError("--slip-detector must be " +
                                     std::string(tactile::control::kSlipDetectorNames) + "; got '" +
                                     slip_detector + "'");
    }
    tactile::rig::Scenario scenario = tactile::rig::load_scenario(scenario_path);
    if (!slip_detector.empty()) scenario.slip_detector = slip_detector;
    if (!grip.empty()) scenario.grip = grip;
    if (!cameras.empty()) {
      if (cameras.size() != 2) {
        throw tactile::cli::UsageError("--cameras needs two addresses, left,right; got '" +
                                       fmt::format("{}", fmt::join(cameras, ",")) + "'");
      }
      rt.camera_addresses = {cameras[0], cameras[1]};
    }
    if (!observe_frames.empty()) rt.observe_frames = observe_frames;
    if (!arm_key.empty()) {
      tactile::wire::ServerSecurity sec{tactile::wire::load_key_pair(arm_key), {}};
      for (const std::string& c : arm_clients)
        sec.authorized_clients.push_back(tactile::wire::load_public_key(c));
      rt.arm_security = std::move(sec);
    } else if (!arm_clients.empty()) {
      throw tactile::cli::UsageError("--arm-client needs --arm-key");
    }
    if (!observe_key.empty()) {
      // sensor_node's PUB lets in any client that knows its public key: the rig's own pair is new.
      rt.observe_security = tactile::wire::ClientSecurity{
          tactile::wire::generate_keypair(), tactile::wire::load_public_key(observe_key)};
    }
    if (!observe_events_key.empty()) {
      rt.observe_events_security = tactile::wire::ClientSecurity{
          tactile::wire::generate_keypair(), tactile::wire::load_public_key(observe_events_key)};
    }
    if (!truth_key.empty()) {
      rt.truth_security =
          tactile::wire::ServerSecurity{tactile::wire::load_key_pair(truth_key), {}};
    }
    if (!write_configs.empty()) {
      tactile::rig::write_node_configs(scenario, write_configs, rt);
      tactile::util::log_info(
          "wrote left.yaml, right.yaml, sensor_node.yaml and hand_node.yaml into {}",
          write_configs);
      return 0;
    }
    tactile::util::log_info(
        "{} ({}): {}", scenario_path, lockstep ? "lockstep" : "real time",
        tactile::control::describe_controller(tactile::rig::scenario_controller_config(scenario)));
    // The results are written at the end of a run that may last minutes: a folder that cannot take
    // them is refused now, not found out then.
    for (const std::string& file : {report_path, series_path, timing_path}) {
      if (!file.empty())
        tactile::util::check_writable_dir(std::filesystem::path(file).parent_path());
    }
    for (const std::string& dir : {plots_dir, calibration_dir}) {
      if (!dir.empty()) tactile::util::check_writable_dir(dir);
    }
    if (!lockstep) {
      tactile::util::install_stop_handlers();
      tactile::wire::install_protobuf_log_handler();
      rt.record_series = !plots_dir.empty() || !series_path.empty();
      tactile::util::ReadyFile ready(ready_path);
      rt.on_ready = [&ready] { ready.mark_ready(); };
      const tactile::rig::RealtimeResult result = tactile::rig::run_realtime(scenario, rt);
      const std::string json = tactile::rig::report_json(result.run.report);
      if (!report_path.empty()) {
        tactile::util::write_file_atomic(report_path, json);
        tactile::util::log_info("report written to {}", report_path);
      } else {
        std::fputs(json.c_str(), stdout);
      }
      if (!series_path.empty()) {
        tactile::util::write_file_atomic(series_path, tactile::rig::series_csv(result.run.series));
      }
      if (!plots_dir.empty()) {
        const auto controller = tactile::rig::scenario_controller_config(scenario);
        for (const auto& path : tactile::rig::write_plots(result.run, controller, plots_dir)) {
          tactile::util::log_info("wrote {}", path.string());
        }
        if (!result.latency_ms.empty()) {
          tactile::util::log_info(
              "wrote {}", tactile::rig::write_latency_plot(result.latency_ms, plots_dir).string());
        }
      }
      return 0;
    }
    tactile::rig::LockstepOptions options;
    options.dt_s = dt_s;
    options.record_series = !plots_dir.empty() || !series_path.empty();
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    const tactile::rig::LockstepResult result = tactile::rig::run_lockstep(scenario, options);
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    const double sim_s = result.report.sim_time_s;
    const double ratio = sim_s > 0 ? wall_s / sim_s : 0.0;
    const double cpu_ratio = sim_s > 0 ? cpu_s / sim_s : 0.0;
    tactile::util::log_info(
        "simulated {:.2f} s in {:.2f} s wall ({:.3f} of simulated time), {:.2f} s CPU ({:.3f}), {}",
        sim_s, wall_s, ratio, cpu_s, cpu_ratio, result.report.end_reason);

    const std::string json = tactile::rig::report_json(result.report);
    if (!report_path.empty()) {
      tactile::util::write_file_atomic(report_path, json);
    } else {
      std::fputs(json.c_str(), stdout);
    }
    if (!timing_path.empty()) {
      tactile::util::write_file_atomic(
          timing_path,
          fmt::format("{{\"wall_s\": {:.4f}, \"cpu_s\": {:.4f}, \"sim_time_s\": {:.4f}, "
                      "\"wall_over_sim\": {:.5f}, \"cpu_over_sim\": {:.5f}}}\n",
                      wall_s, cpu_s, sim_s, ratio, cpu_ratio));
    }
    if (!calibration_dir.empty()) {
      for (const std::filesystem::path& path :
           tactile::rig::save_calibrations(calibration_dir, result.calibrations)) {
        tactile::util::log_info("wrote {}", path.string());
      }
    }
    if (!series_path.empty()) {
      tactile::util::write_file_atomic(series_path, tactile::rig::series_csv(result.series));
      std::filesystem::path mismatch_path(series_path);
      mismatch_path.replace_extension(".mismatches.csv");
      tactile::util::write_file_atomic(mismatch_path, tactile::rig::mismatches_csv(result.series));
    }
    if (!plots_dir.empty()) {
      const auto controller = tactile::rig::scenario_controller_config(scenario);
      for (const auto& path : tactile::rig::write_plots(result, controller, plots_dir))
        tactile::util::log_info("wrote {}", path.string());
    }
    return 0;
  });
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("rig");
  return run(argc, argv);
}
