#pragma once

// The recorded capture the latency tests run on (tests/data/latency/capture.tlog, written by
// make_latency_capture, whose header comment gives the run) and its measured window.
#include <cstdint>
#include <filesystem>

#include "latency_analysis.hpp"

namespace tactile::bench::testing {

inline constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;  // exposure 0's camera timestamp
inline constexpr std::int64_t kMs = 1'000'000;
inline constexpr double kFps = 100;

inline std::filesystem::path recorded_capture() {
  return std::filesystem::path(TACTILE_TEST_DATA) / "latency" / "capture.tlog";
}

// Exposures 5..24 (camera timestamps, and the commands sent 1.94 ms after each).
inline Window recorded_window() {
  Window w;
  w.begin_ns = kT0 + 50 * kMs;
  w.end_ns = kT0 + 250 * kMs - 1;
  w.all_running = true;
  return w;
}

// The capture analysed over its window.
inline PipelineResult recorded_analysis() {
  PipelineResult r;
  r.fps = kFps;
  r.window_s = 0.2;
  analyse_capture(read_capture(recorded_capture()), recorded_window(), kFps, r);
  return r;
}

}  // namespace tactile::bench::testing
