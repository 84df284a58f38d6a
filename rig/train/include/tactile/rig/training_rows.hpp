#pragma once

// The learned slip detector's training rows as a file (docs/slip.md, "Training on a cluster"):
// `slip_train --shard K/N --rows-out FILE` runs part of the training runs and writes their rows;
// `slip_train --rows-in FILE...` reads every shard's rows and fits once, to the same model as one
// process that ran every run. The floats are stored as their bytes, so the fit sees the very
// values the runs logged. Pure: text in, text out.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tactile::rig::train {

// One training run's rows: `features` floats per row, its label and weight.
struct RowsOfRun {
  std::uint64_t seed = 0;
  std::uint64_t index = 0;
  std::vector<float> x;  // rows x features, row-major
  std::vector<std::uint8_t> label;
  std::vector<float> weight;
};

// What one shard wrote: the options every shard must share (the runs they split), its part, and
// the rows of its runs.
struct TrainingRows {
  std::vector<std::uint64_t> seeds;
  std::uint64_t scenarios = 0;  // per seed
  double max_time_s = 0;
  std::string controller;
  // The grip of the training runs: paper, margin, or mixed (the odd scenarios of each seed under
  // the margin grip, the even under the paper's). Files without the key were made with paper.
  std::string grip = "paper";
  // A lab's sensor the runs rendered (slip_train --calibration, absolute); empty: the rig's own.
  // Written only when set, so files without it keep their bytes.
  std::string calibration;
  // The sweep's sensor set the runs drew (slip_train --sensor: rig, feelers or drawn). Written
  // only when not rig, so files without it keep their bytes.
  std::string sensor = "rig";
  std::size_t features = 0;
  int shard = 1;  // K of shards
  int shards = 1;
  std::vector<RowsOfRun> runs;
};

// The file's bytes: a JSON header line (`tactile-slip-rows/1`), then each run's counts and rows in
// little-endian binary.
std::string rows_file(const TrainingRows& rows);
// Reads rows_file()'s output; throws std::runtime_error naming `source` for a bad or cut file.
TrainingRows parse_rows_file(std::string_view bytes, const std::string& source);

}  // namespace tactile::rig::train
