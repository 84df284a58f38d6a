#pragma once

// "N % of FILE read (R records)" in the log every `step_ns` while a tool reads a long log
// (tactile_replay --info and --remeasure, tactile_mcap). Header-only: the tools link util.
#include <algorithm>
#include <cstdint>

#include "tactile/recording/log_reader.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"

namespace tactile::recording {

class ReadProgress {
 public:
  // step_ns <= 0: never logs.
  explicit ReadProgress(const LogReader& reader, std::int64_t step_ns = 2'000'000'000)
      : reader_(reader), step_ns_(step_ns), next_(util::monotonic_ns() + step_ns) {}

  // After `records` records: logs when a step has passed since the last line.
  void tick(std::uint64_t records) {
    if (step_ns_ <= 0) return;
    const std::int64_t now = util::monotonic_ns();
    if (now < next_) return;
    next_ = now + step_ns_;
    const double total = static_cast<double>(std::max<std::uint64_t>(reader_.file_size(), 1));
    util::log_info("{:.0f} % of {} read ({} records)",
                   100.0 * static_cast<double>(reader_.position()) / total, reader_.path().string(),
                   records);
  }

 private:
  const LogReader& reader_;
  std::int64_t step_ns_;
  std::int64_t next_;
};

}  // namespace tactile::recording
