// sensor_node: grabs frames from the tactile sensors' cameras through Aravis, measures every
// sensing element and publishes TactileFrames over ZeroMQ.
#include <CLI/CLI.hpp>
#include <atomic>
#include <thread>

#include "src/pipeline.hpp"
#include "src/sensor_config.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/realtime.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"

namespace {

using tactile::sensor::CameraConfig;
using tactile::sensor::SensorConfig;

int run(int argc, char** argv) {
  std::string config_path;
  std::string camera;
  std::string calibration;
  std::string reference;
  std::string publish;
  std::string state_dir;
  std::string ready_path;
  std::string log_level = "info";
  double fps = 0;
  bool raw_frames = false;
  CLI::App app{
      "sensor_node: the sensor PC of the tactile slippage control system. Grabs GigE Vision "
      "frames through Aravis from the cameras inside the optical three-axis tactile sensors, "
      "measures each sensing element (G, centroid, displacement, tri-axial force) and "
      "publishes TactileFrames over ZeroMQ."};
  app.add_option("--config", config_path, "configuration file (tactile-sensor/1 YAML)");
  app.add_option("--camera", camera,
                 "one-camera case: IPv4 address or Aravis device id of the camera")
      ->check(tactile::cli::non_empty());
  app.add_option("--calibration", calibration, "one-camera case: calibration file of its sensor")
      ->check(tactile::cli::non_empty());
  app.add_option("--reference", reference,
                 "one-camera case: use this no-load frame (PGM) instead of capturing one")
      ->check(tactile::cli::non_empty());
  app.add_option("--publish", publish,
                 "PUB endpoint (default tcp://*:5555 or the file's); several comma-separated, e.g. "
                 "tcp://*:5555,ipc:///tmp/sensor.ipc")
      ->check(tactile::cli::non_empty());
  app.add_option("--state-dir", state_dir,
                 "folder for what sensor_node keeps between runs (relative reference_cache paths); "
                 "default: the "
                 "configuration file's folder");
  app.add_option("--fps", fps, "one-camera case: frame rate (default 100 or the file's)");
  app.add_flag("--raw-frames", raw_frames,
               "also publish every measured camera frame and the reference on raw/<sensor_id> "
               "(docs/recording.md)");
  app.add_option("--ready-file", ready_path,
                 "write this file once every camera's frames are measured and published, and "
                 "remove it on exit (a health check, docker/compose.yaml)");
  std::string roi;
  app.add_option("--roi", roi,
                 "every camera's region of interest: auto (the rows and columns that hold the "
                 "elements; the default) or full (whole frames); overrides the configuration's "
                 "roi")
      ->check(CLI::IsMember({"auto", "full"}));
  tactile::cli::add_log_level(app, log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    tactile::util::set_log_level(tactile::util::parse_log_level(log_level));
    std::vector<std::string> warnings;
    SensorConfig cfg = tactile::sensor::default_sensor_config();
    if (!config_path.empty()) {
      cfg = tactile::sensor::load_sensor_config(config_path, &warnings, state_dir);
    } else if (camera.empty() || calibration.empty()) {
      throw tactile::cli::UsageError("give --config FILE, or --camera and --calibration");
    }
    const bool one_camera =
        !camera.empty() || !calibration.empty() || !reference.empty() || fps > 0;
    if (one_camera) {
      if (cfg.cameras.size() > 1) {
        throw tactile::cli::UsageError(
            "--camera, --calibration, --reference and --fps need a one-camera configuration");
      }
      if (cfg.cameras.empty()) cfg.cameras.emplace_back();
      CameraConfig& c = cfg.cameras.front();
      if (!calibration.empty()) {
        c.calibration_path = calibration;
        c.calibration = tactile::config::load_calibration(calibration, &warnings);
        c.sensor_id = c.calibration.sensor_id;
      }
      if (!camera.empty()) c.camera.camera = camera;
      if (!reference.empty()) c.reference = reference;
      if (fps > 0) c.camera.frame_rate_hz = fps;
      if (c.camera.camera.empty()) throw std::invalid_argument("no camera given (--camera)");
      tactile::sensor::finish_camera_config(c);
    }
    if (!roi.empty()) {
      for (CameraConfig& c : cfg.cameras) {
        c.roi_auto = roi == "auto";
        tactile::sensor::finish_camera_config(c);
      }
    }
    if (!publish.empty()) cfg.publish = publish;
    if (raw_frames) cfg.raw_frames = true;
    for (const auto& w : warnings)
      tactile::util::log_warn("{}", w);

    // Before any thread exists, so that ZeroMQ's and Aravis's threads inherit it.
    tactile::util::apply_realtime_scheduling(cfg.realtime, config_path + ": realtime");
    if (cfg.realtime.priority != 0 || cfg.realtime.lock_memory)
      tactile::util::log_info("real-time scheduling: {}", tactile::util::describe(cfg.realtime));
    tactile::util::install_stop_handlers();
    tactile::wire::install_protobuf_log_handler();
    tactile::util::ReadyFile ready(ready_path);
    zmq::context_t ctx;
    tactile::sensor::SharedPublisher pub(
        ctx, cfg.publish, cfg.security ? &*cfg.security : nullptr,
        cfg.raw_frames ? tactile::sensor::kRawFramesSendQueue : tactile::wire::kDefaultSendQueue);
    tactile::util::log_info("publishing on {}{}", pub.endpoint(), cfg.security ? " (CURVE)" : "");
    std::vector<std::unique_ptr<tactile::sensor::Pipeline>> pipelines;
    for (const CameraConfig& c : cfg.cameras) {
      pipelines.push_back(std::make_unique<tactile::sensor::Pipeline>(
          c, cfg.measurement, cfg.stats_period_s, cfg.raw_frames,
          std::make_unique<tactile::camera::AravisCamera>(c.camera), pub));
    }
    std::atomic<bool> stop{false};
    std::vector<std::thread> threads;
    for (auto& p : pipelines)
      threads.emplace_back([&p, &stop] { p->run(stop); });
    // The threads end on their own only after a fatal error; a signal ends them all.
    bool announced_ready = false;
    while (!tactile::util::stop_requested()) {
      bool fatal = false;
      bool measuring = true;
      for (const auto& p : pipelines) {
        fatal = fatal || !p->fatal_error().empty();
        measuring = measuring && p->counters().complete.load() > 0;
      }
      if (fatal) break;
      if (measuring && !announced_ready) {
        announced_ready = true;
        tactile::util::log_info("every camera is measured and published");
        try {
          ready.mark_ready();
        } catch (const std::exception& e) {
          tactile::util::log_warn("{}", e.what());  // the health check then fails, visibly
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    stop = true;
    for (auto& t : threads)
      t.join();
    int code = 0;
    for (const auto& p : pipelines) {
      if (!p->fatal_error().empty()) code = 1;
      tactile::util::log_info(
          "published {} frames ({} measured, {} not measured), camera restarts {}",
          p->counters().published.load(), p->counters().complete.load(),
          p->counters().not_measured.load(), p->counters().camera_restarts.load());
    }
    return code;
  });
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("sensor_node");
  return run(argc, argv);
}
