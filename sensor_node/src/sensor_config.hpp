#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/camera/aravis_camera.hpp"
#include "tactile/extractor.hpp"
#include "tactile/util/realtime.hpp"
#include "tactile/wire/security.hpp"

namespace tactile::sensor {

inline constexpr const char* kSensorConfigFormat = "tactile-sensor/1";

struct CameraConfig {
  std::string sensor_id;
  std::filesystem::path calibration_path;
  Calibration calibration;
  camera::AravisCameraOptions camera;     // width, height and pixel format from the calibration
  std::filesystem::path reference;        // a no-load frame to use instead of capturing one
  std::filesystem::path reference_cache;  // a captured reference is saved here and reused
  // The camera's region of interest: true (`roi: auto`, the default) receives only the rows and
  // columns that hold the calibration's disks, grown to the camera's increments; false
  // (`roi: full`) whole frames.
  bool roi_auto = true;
  double frame_timeout_s = 0.5;  // no frame for this long: the camera stopped; reopen it
  double retry_initial_s = 0.2;  // first wait before reopening, doubled up to retry_max_s
  double retry_max_s = 5.0;
};

// sensor_node's configuration (docs/sensor_node.md).
struct SensorConfig {
  std::string publish = "tcp://*:5555";
  double stats_period_s = 1.0;
  // Publish every measured camera frame and the reference in use on topic raw/<sensor_id>
  // (docs/recording.md), so a recorded run can be measured again bit for bit. Large: off by
  // default.
  bool raw_frames = false;
  ExtractorOptions measurement;
  std::vector<CameraConfig> cameras;
  // CURVE on the PUB socket (docs/security.md); unset: plain TCP.
  std::optional<wire::ServerSecurity> security;
  // SCHED_FIFO and locked memory for the whole program (docs/deployment.md); default: neither.
  util::RealtimeScheduling realtime;
};

SensorConfig default_sensor_config();

// Loads and checks a file; throws config::ConfigError naming file, line, key and value. Paths in
// the file are relative to its folder, but a relative reference_cache is relative to
// `state_dir` when one is given (a writable place for what the program keeps between runs).
SensorConfig load_sensor_config(const std::filesystem::path& path,
                                std::vector<std::string>* warnings,
                                const std::filesystem::path& state_dir = {});

// Fills the camera's image settings (size, pixel format, region of interest) from its
// calibration and roi_auto, and checks them.
void finish_camera_config(CameraConfig& c);

}  // namespace tactile::sensor
