// libFuzzer target: hand_node's configuration loader (hand_node/src/hand_config.cpp, built here
// on its own). Promises: only config::ConfigError escapes, with a one-line message; an accepted
// file names two different fingertips whose calibrations validate, with one unit normal per
// element, and usable periods.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "config_fuzz.hpp"
#include "hand_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tactile;
  static const fuzz::ConfigFolder folder;
  const auto path = folder.write(data, size);
  fuzz::expect_loaded_or_config_error([&] {
    std::vector<std::string> warnings;
    const hand::HandConfig cfg = hand::load_hand_config(path, &warnings);
    fuzz::require(cfg.fingertips[0].sensor_id != cfg.fingertips[1].sensor_id,
                  "both fingertips have one sensor id");
    for (const auto& f : cfg.fingertips) {
      validate(f.calibration);  // throws CalibrationError: escapes as a finding
      fuzz::require(f.normals.size() == f.calibration.elements.size(), "a normal per element");
    }
    fuzz::require(!cfg.subscribe.empty(), "no sensor_node endpoint");
    for (double v : {cfg.heartbeat_period_s, cfg.control_period_s, cfg.arm_timeout_s})
      fuzz::require(v > 0 && std::isfinite(v), "a period is not positive and finite");
    fuzz::require(cfg.pair_window_s >= 0 && cfg.pair_window_s <= 1, "pair_window_s out of 0..1");
  });
  return 0;
}
