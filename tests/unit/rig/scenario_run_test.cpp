// The one scenario core of the lockstep and real-time runs (rig/lockstep's ScenarioRun): what
// it decides by itself, on time given as an argument. The lockstep runner's whole runs are in
// lockstep_test.cpp; the real-time run against the lockstep run of one file in
// tests/integration/system (LoopbackSystem).
#include "tactile/rig/scenario_run.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace tactile::rig {
namespace {

const std::filesystem::path kDir = TACTILE_RIG_SCENARIOS;

TEST(ScenarioRun, OpensInTheAirOnlyWhenOpenLeavesTheCapUnsupported) {
  struct Row {
    control::CommandKind command;
    CapPlace cap;
    bool in_air;
  };
  const Row rows[] = {
      {control::CommandKind::kOpen, CapPlace::kFree, true},
      {control::CommandKind::kOpen, CapPlace::kOnTable, false},
      {control::CommandKind::kOpen, CapPlace::kOnBottle, false},
      {control::CommandKind::kOpen, CapPlace::kThreaded, false},
      {control::CommandKind::kHold, CapPlace::kFree, false},
      {control::CommandKind::kStop, CapPlace::kFree, false},
      {control::CommandKind::kMoveTo, CapPlace::kFree, false},
      {control::CommandKind::kFingerVelocities, CapPlace::kFree, false},
      {control::CommandKind::kNone, CapPlace::kFree, false},
  };
  for (const Row& r : rows) {
    EXPECT_EQ(opens_in_air(r.command, r.cap), r.in_air)
        << control::to_string(r.command) << " with the cap " << to_string(r.cap);
  }
}

class ScenarioRunTest : public ::testing::Test {
 protected:
  Scenario sc_ = load_scenario(kDir / "default.yaml");
  LockstepResult result_;
  ScenarioRun run_{sc_, sc_.camera, result_, false};
};

TEST_F(ScenarioRunTest, SetsTheReportsCaseAndCalibrationsAtTheStart) {
  EXPECT_EQ(result_.report.seed, sc_.seed);
  EXPECT_EQ(result_.report.scenario_case, "normal");
  EXPECT_EQ(result_.report.end_reason, "max_time");
  EXPECT_GT(result_.report.hold.grip_allowed_n, 0.0);
  for (const Calibration& c : result_.calibrations)
    EXPECT_FALSE(c.elements.empty());
}

TEST_F(ScenarioRunTest, AnOpenOnTheTableIsNoDrop) {
  ASSERT_TRUE(run_.step(10, sc_.step_s()));
  ASSERT_EQ(run_.world().cap().place, CapPlace::kOnTable);
  run_.apply(control::Command::open_fingers({0.01, 0.005}));
  EXPECT_FALSE(result_.report.opened_in_air);
}

TEST_F(ScenarioRunTest, ACompletedTaskEndsAfterTheSettleTimeAsDone) {
  result_.report.completed = true;  // the scorer's DONE event
  run_.task_ended(2.0);
  run_.task_ended(5.0);  // the first end counts
  EXPECT_EQ(result_.report.end_reason, "done");
  EXPECT_FALSE(run_.ended_after_frame(201, 2.0 + sc_.settle_after_done_s / 2));
  EXPECT_TRUE(run_.ended_after_frame(240, 2.0 + sc_.settle_after_done_s + 0.01));
}

TEST_F(ScenarioRunTest, AnAbortedTaskKeepsItsReason) {
  result_.report.end_reason = "aborted: lowered to lower_limit_m";  // the scorer's ABORTED event
  run_.task_ended(3.0);
  EXPECT_TRUE(run_.ended_after_frame(400, 3.0 + sc_.settle_after_done_s + 0.01));
  EXPECT_EQ(result_.report.end_reason, "aborted: lowered to lower_limit_m");
}

TEST_F(ScenarioRunTest, EndsAtMaxTimeCountedInFrames) {
  const auto frames = static_cast<std::uint64_t>(std::ceil(sc_.max_time_s * sc_.camera.fps));
  EXPECT_FALSE(run_.ended_after_frame(frames - 1, sc_.max_time_s));
  EXPECT_TRUE(run_.ended_after_frame(frames, sc_.max_time_s));
  EXPECT_EQ(result_.report.end_reason, "max_time");
}

TEST_F(ScenarioRunTest, TheArmFeedbackIsTheWorldsArm) {
  const control::ArmFeedback f = arm_feedback(run_.world());
  const ArmState& arm = run_.world().arm();
  EXPECT_EQ(f.wrist.position_m.z, arm.position_m.z);
  EXPECT_EQ(f.wrist.yaw_rad, arm.yaw_rad);
  EXPECT_EQ(f.segment_done, arm.segment_done);
  EXPECT_EQ(f.holding, arm.holding || arm.stopped);
  for (std::size_t i = 0; i < kFingertips; ++i)
    EXPECT_EQ(f.fingertip_position_m[i].x, run_.world().fingertip(i).offset_w.x);
  run_.apply(control::Command::stop());
  EXPECT_TRUE(arm_feedback(run_.world()).holding);  // a stopped arm holds
}

}  // namespace
}  // namespace tactile::rig
