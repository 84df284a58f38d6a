// The longer packet-loss sweep (ctest label "slow"): 3000 frames (30 s) per loss level, from the
// rig's in-process camera and from nft, every frame checked against the truth as in loss_test.
#include <gtest/gtest.h>

#include <ostream>

#include "fault_support.hpp"
#include "loss_expectations.hpp"

namespace tactile::faults {
namespace {

struct Level {
  const char* name;
  double gvsp_lost_ratio;
  int nft_percent;
};

void PrintTo(const Level& level, std::ostream* os) {
  *os << level.name;
}

class LossSweep : public ::testing::TestWithParam<Level> {};

TEST_P(LossSweep, ThreeThousandFramesAgainstTheTruth) {
  LossSetup setup;
  setup.gvsp_lost_ratio = GetParam().gvsp_lost_ratio;
  setup.nft_percent = GetParam().nft_percent;
  setup.frames = 3000;
  setup.limit = std::chrono::seconds(90);
  const LossRun run = run_sensor_node_under_loss(TACTILE_SENSOR_NODE_PATH, setup);
  expect_loss_handled(run);
  const TruthReport& t = run.truth;
  // One line per level for docs/reliability.md.
  std::printf("| %s | %zu | %zu | %zu | %.1f %% | %zu | %zu | %zu | %zu |\n", GetParam().name,
              t.frames, t.complete, t.incomplete,
              100.0 * static_cast<double>(t.incomplete) / static_cast<double>(t.frames),
              t.never_received, t.stale_id, t.complete_after_gap, t.complete_after_complete);
}

INSTANTIATE_TEST_SUITE_P(
    Levels, LossSweep,
    ::testing::Values(Level{"gvsp_0_5_percent", 0.005, 0}, Level{"gvsp_1_percent", 0.01, 0},
                      Level{"gvsp_2_percent", 0.02, 0}, Level{"gvsp_5_percent", 0.05, 0},
                      Level{"gvsp_10_percent", 0.10, 0}, Level{"gvsp_20_percent", 0.20, 0},
                      Level{"nft_1_percent", 0, 1}, Level{"nft_5_percent", 0, 5}),
    [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace tactile::faults
