// Long runs (ctest label "slow"): the step-size independence of the whole scenario's outcome,
// and the variation grid of docs/rig.md against the targets.
#include <gtest/gtest.h>

#include <filesystem>

#include "tactile/rig/lockstep.hpp"

namespace tactile::rig {
namespace {

const std::filesystem::path kDir = TACTILE_RIG_SCENARIOS;

TEST(LockstepSlow, OutcomeIsTheSameWithATenTimesSmallerStep) {
  const Scenario s = load_scenario(kDir / "default.yaml");
  LockstepOptions coarse;
  LockstepOptions fine;
  fine.dt_s = s.step_s() / 10.0;
  const LockstepResult a = run_lockstep(s, coarse);
  const LockstepResult b = run_lockstep(s, fine);
  EXPECT_TRUE(a.physics_finite);
  EXPECT_TRUE(b.physics_finite);
  EXPECT_EQ(a.report.completed, b.report.completed);
  EXPECT_EQ(a.report.dropped, b.report.dropped);
  EXPECT_EQ(a.report.grasp_classified, b.report.grasp_classified);
  EXPECT_EQ(a.report.release_classified, b.report.release_classified);
  EXPECT_EQ(a.report.tightened_cycle, b.report.tightened_cycle);
  EXPECT_EQ(a.report.true_tight_cycle, b.report.true_tight_cycle);
  EXPECT_EQ(a.report.twist_cycles, b.report.twist_cycles);
  EXPECT_EQ(a.report.over_events, b.report.over_events);
  EXPECT_NEAR(a.report.final_cap_angle_deg, b.report.final_cap_angle_deg, 0.5);
  // The same events in the same order.
  std::vector<std::string> ea;
  std::vector<std::string> eb;
  for (const EventRecord& e : a.series.events) {
    if (e.kind_name != "RECOMPRESS") ea.push_back(e.kind_name + "@" + e.phase);
  }
  for (const EventRecord& e : b.series.events) {
    if (e.kind_name != "RECOMPRESS") eb.push_back(e.kind_name + "@" + e.phase);
  }
  EXPECT_EQ(ea, eb);
}

class Variation : public ::testing::TestWithParam<const char*> {};

TEST_P(Variation, MeetsTheOutcomeTargets) {
  const std::string name = GetParam();
  const Scenario s = load_scenario(kDir / "variations" / (name + ".yaml"));
  LockstepOptions o;
  o.record_series = false;
  const Report rep = run_lockstep(s, o).report;
  RecordProperty("report", report_json(rep));
  EXPECT_TRUE(rep.completed) << rep.end_reason;
  EXPECT_FALSE(rep.dropped);
  ASSERT_TRUE(rep.tightened_cycle.has_value());
  EXPECT_EQ(rep.tightened_cycle, rep.true_tight_cycle);
  EXPECT_EQ(rep.over_events, 0);
  EXPECT_LE(rep.force_rmse_normal_N, 0.02 * rep.normal_full_scale_N);
  // The slip targets (precision and recall 0.95, latency p99 2 frames) are not met on every
  // variation: docs/rig.md's table has the figures and the reasons (an ideal sensor does not
  // meet them either). Asserted here is the floor every variation reaches, so that a regression
  // below it fails, and that the measurement loses little to an ideal sensor (at most 0.017 in
  // any variation when this was written).
  EXPECT_GE(rep.slip.precision, 0.85);
  EXPECT_GE(rep.slip.recall, 0.80);
  EXPECT_GE(rep.slip.precision, rep.slip.ideal_precision - 0.03);
  EXPECT_GE(rep.slip.recall, rep.slip.ideal_recall - 0.03);
}

INSTANTIATE_TEST_SUITE_P(Grid, Variation,
                         ::testing::Values("mass-half", "mass-double", "friction-0.5",
                                           "friction-1.0", "vibration-0", "vibration-0.5",
                                           "noise-1", "noise-4", "free-turn-120", "free-turn-480"),
                         [](const ::testing::TestParamInfo<const char*>& p) {
                           std::string n = p.param;
                           for (char& c : n) {
                             if (c == '-' || c == '.') c = '_';
                           }
                           return n;
                         });

}  // namespace
}  // namespace tactile::rig
