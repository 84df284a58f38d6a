// The training rows file (rig/train/training_rows.hpp; docs/slip.md, "Training on a cluster").
#include "tactile/rig/training_rows.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace train = tactile::rig::train;

std::vector<std::uint32_t> bits_of(const std::vector<float>& v) {
  std::vector<std::uint32_t> bits;
  for (const float f : v)
    bits.push_back(std::bit_cast<std::uint32_t>(f));
  return bits;
}

train::TrainingRows sample() {
  train::TrainingRows rows;
  rows.seeds = {101, 7};
  rows.scenarios = 3;
  rows.max_time_s = 6.5;
  rows.controller = "learned";
  rows.features = 3;
  rows.shard = 2;
  rows.shards = 3;
  // Values a text format could lose: -0, a subnormal, infinity, NaN, the largest float.
  rows.runs.push_back(
      {101,
       1,
       {-0.0F, std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::infinity(),
        1.0F / 3.0F, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::max()},
       {1, 0},
       {8.0F, 0.1F}});
  rows.runs.push_back({7, 2, {}, {}, {}});  // a run with no rows
  return rows;
}

TEST(TrainingRows, RoundTripsBitForBit) {
  const train::TrainingRows rows = sample();
  const std::string bytes = train::rows_file(rows);
  const train::TrainingRows back = train::parse_rows_file(bytes, "x.rows");
  EXPECT_EQ(back.seeds, rows.seeds);
  EXPECT_EQ(back.scenarios, rows.scenarios);
  EXPECT_EQ(back.max_time_s, rows.max_time_s);
  EXPECT_EQ(back.controller, rows.controller);
  EXPECT_EQ(back.features, rows.features);
  EXPECT_EQ(back.shard, 2);
  EXPECT_EQ(back.shards, 3);
  ASSERT_EQ(back.runs.size(), 2U);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(back.runs[k].seed, rows.runs[k].seed);
    EXPECT_EQ(back.runs[k].index, rows.runs[k].index);
    EXPECT_EQ(back.runs[k].label, rows.runs[k].label);
    ASSERT_EQ(back.runs[k].x.size(), rows.runs[k].x.size());
    ASSERT_EQ(back.runs[k].weight.size(), rows.runs[k].weight.size());
    // The floats' bits (an empty run's vectors may hold no storage: compared as bit lists).
    EXPECT_EQ(bits_of(back.runs[k].x), bits_of(rows.runs[k].x)) << "run " << k;
    EXPECT_EQ(bits_of(back.runs[k].weight), bits_of(rows.runs[k].weight)) << "run " << k;
  }
  EXPECT_EQ(train::rows_file(back), bytes);
}

// slip_train --calibration: the header says the lab's file, and a file without one has no key
// (its bytes as before).
TEST(TrainingRows, TheLabsCalibrationRoundTripsAndIsAbsentWithoutOne) {
  train::TrainingRows rows = sample();
  EXPECT_EQ(train::rows_file(rows).find("calibration"), std::string::npos);
  EXPECT_EQ(train::parse_rows_file(train::rows_file(rows), "x.rows").calibration, "");
  rows.calibration = "/labs/left.yaml";
  const std::string bytes = train::rows_file(rows);
  EXPECT_EQ(train::parse_rows_file(bytes, "x.rows").calibration, "/labs/left.yaml");
  EXPECT_EQ(train::rows_file(train::parse_rows_file(bytes, "x.rows")), bytes);
}

// slip_train --sensor: the header says a set other than the rig's, and a file without the key is
// the rig's (its bytes as before).
TEST(TrainingRows, TheSensorSetRoundTripsAndIsAbsentForTheRigs) {
  train::TrainingRows rows = sample();
  EXPECT_EQ(train::rows_file(rows).find("sensor"), std::string::npos);
  EXPECT_EQ(train::parse_rows_file(train::rows_file(rows), "x.rows").sensor, "rig");
  rows.sensor = "drawn";
  const std::string bytes = train::rows_file(rows);
  EXPECT_NE(bytes.find("\"sensor\":\"drawn\""), std::string::npos);
  EXPECT_EQ(train::parse_rows_file(bytes, "x.rows").sensor, "drawn");
  EXPECT_EQ(train::rows_file(train::parse_rows_file(bytes, "x.rows")), bytes);
}

TEST(TrainingRows, EveryCutAndAnyTrailingByteIsRefusedNamingTheFile) {
  const std::string bytes = train::rows_file(sample());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    try {
      (void)train::parse_rows_file(bytes.substr(0, n), "cut.rows");
      ADD_FAILURE() << "a file cut to " << n << " of " << bytes.size() << " bytes was read";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cut.rows: ", 0), 0U) << e.what();
    }
  }
  EXPECT_THROW((void)train::parse_rows_file(bytes + "x", "long.rows"), std::runtime_error);
}

TEST(TrainingRows, ABadHeaderOrRowCountIsRefusedBeforeAnyAllocation) {
  std::string bytes = train::rows_file(sample());
  const std::string header = bytes.substr(0, bytes.find('\n'));
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"\"features\":3", "\"features\":1000000000000"},
           {"\"features\":3", "\"features\":0"},
           {"tactile-slip-rows/1", "tactile-slip-rows/2"},
           {"\"runs\":2", "\"runs\":\"two\""}}) {
    std::string bad = bytes;
    bad.replace(bad.find(from), from.size(), to);
    EXPECT_THROW((void)train::parse_rows_file(bad, "bad.rows"), std::runtime_error) << to;
  }
  // Run 0's row count (after its seed and index) set huge: refused, not allocated.
  const std::size_t count_at = header.size() + 1 + 2 * sizeof(std::uint64_t);
  const std::uint64_t huge = std::uint64_t{1} << 60;
  std::memcpy(bytes.data() + count_at, &huge, sizeof huge);
  EXPECT_THROW((void)train::parse_rows_file(bytes, "huge.rows"), std::runtime_error);
  // Rows that do not fit the feature count are not written.
  train::TrainingRows rows = sample();
  rows.runs[0].x.pop_back();
  EXPECT_THROW((void)train::rows_file(rows), std::invalid_argument);
}

}  // namespace
