// libFuzzer target: sensor_node's configuration loader (sensor_node/src/sensor_config.cpp, built
// here on its own). Promises: only config::ConfigError escapes, with a one-line message; an
// accepted file gives cameras whose calibration validates and whose numbers are usable.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "config_fuzz.hpp"
#include "sensor_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tactile;
  static const fuzz::ConfigFolder folder;
  const auto path = folder.write(data, size);
  fuzz::expect_loaded_or_config_error([&] {
    std::vector<std::string> warnings;
    const sensor::SensorConfig cfg = sensor::load_sensor_config(path, &warnings);
    fuzz::require(!cfg.cameras.empty(), "accepted a configuration without cameras");
    fuzz::require(cfg.stats_period_s > 0 && std::isfinite(cfg.stats_period_s), "stats period");
    fuzz::require(cfg.measurement.max_gap_frames >= 1, "max_gap_frames below 1");
    for (const auto& c : cfg.cameras) {
      validate(c.calibration);  // throws CalibrationError: escapes as a finding
      fuzz::require(c.calibration.sensor_id == c.sensor_id, "calibration of another sensor");
      fuzz::require(c.camera.width == c.calibration.width, "camera width not the calibration's");
      fuzz::require(c.camera.height == c.calibration.height, "camera height not the calibration's");
      for (double v : {c.frame_timeout_s, c.retry_initial_s, c.retry_max_s, c.camera.frame_rate_hz})
        fuzz::require(v > 0 && std::isfinite(v), "a time or rate is not positive and finite");
    }
  });
  return 0;
}
