// rig: the simulated rig (docs/rig.md). `rig --lockstep --scenario FILE --report FILE.json` runs
// the scenario in one process on simulated time; the real-time mode is not built yet.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <string>

#include "tactile/config/calibration_file.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/plots.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"

namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "rig: the simulated rig of the tactile slippage control system (docs/rig.md).\n"
      "  rig --lockstep --scenario FILE --report FILE.json [--plots DIR]\n"
      "runs the grasp-move-twist scenario in one process on simulated time, with the real\n"
      "measurement and control cores in the loop; the same seed gives the same report."};
  std::string scenario_path;
  std::string report_path;
  std::string plots_dir;
  std::string timing_path;
  std::string series_path;
  std::string calibration_dir;
  bool lockstep = false;
  double dt_s = 0;
  std::string log_level = "info";
  app.add_option("--scenario", scenario_path, "scenario file (tactile-scenario/1)")->required();
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
  app.add_option("--log-level", log_level, "debug, info, warn or error");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "rig: %s (see --help)\n", e.what());
    return 2;
  }
  tactile::util::set_program_name("rig");
  try {
    tactile::util::set_log_level(tactile::util::parse_log_level(log_level));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rig: --log-level: %s\n", e.what());
    return 2;
  }
  if (!lockstep) {
    std::fprintf(stderr,
                 "rig: the real-time mode (fake GigE Vision cameras and arm controller) is not "
                 "built yet; run with --lockstep\n");
    return 3;
  }

  const tactile::rig::Scenario scenario = tactile::rig::load_scenario(scenario_path);
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
        timing_path, fmt::format("{{\"wall_s\": {:.4f}, \"cpu_s\": {:.4f}, \"sim_time_s\": {:.4f}, "
                                 "\"wall_over_sim\": {:.5f}, \"cpu_over_sim\": {:.5f}}}\n",
                                 wall_s, cpu_s, sim_s, ratio, cpu_ratio));
  }
  if (!calibration_dir.empty()) {
    for (const tactile::Calibration& cal : result.calibrations) {
      const std::filesystem::path path =
          std::filesystem::path(calibration_dir) / (cal.sensor_id + ".yaml");
      tactile::config::save_calibration(path, cal);
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
    for (const auto& path : tactile::rig::write_plots(result, plots_dir))
      tactile::util::log_info("wrote {}", path.string());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rig: %s\n", e.what());
    return 1;
  }
}
