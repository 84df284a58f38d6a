#pragma once

#include <cstdint>
#include <ctime>

namespace tactile::util {

// Wall-clock time (CLOCK_REALTIME) in nanoseconds: the time base of every *_timestamp_ns on
// the wire. Programs only; the cores take time as an argument.
inline std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

// Monotonic time in nanoseconds, for periods and timeouts.
inline std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

}  // namespace tactile::util
