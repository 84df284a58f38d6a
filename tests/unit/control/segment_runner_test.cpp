// The segment runner: one trajectory segment at a time, done by its own id only, the timeout
// strict, a resumed segment under a new id.
#include "tactile/control/segment_runner.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>

namespace tactile::control {
namespace {

constexpr double kTimeoutS = 2.0;
constexpr double kIssuedS = 1.0;

MoveTo carry() {
  return MoveTo{0, "MOVE3", {{0.1, 0.2, 0.3}, 0.5}, 0.05, 1.0, true};
}

struct PollRow {
  const char* name;
  bool issued;
  int reported_id_offset;  // the arm's segment id relative to the issued one
  bool reported_done;
  double t;
  SegmentStatus expected;
};
void PrintTo(const PollRow& row, std::ostream* os) {
  *os << row.name;
}

class Poll : public ::testing::TestWithParam<PollRow> {};

TEST_P(Poll, Status) {
  const PollRow& row = GetParam();
  SegmentIds ids;
  SegmentRunner runner(kTimeoutS);
  std::uint32_t id = 0;
  if (row.issued) id = runner.issue(carry(), kIssuedS, ids).move_to.segment_id;
  ArmFeedback arm;
  arm.active_segment_id = id + static_cast<std::uint32_t>(row.reported_id_offset);
  arm.segment_done = row.reported_done;
  EXPECT_EQ(runner.poll(arm, row.t), row.expected);
  const bool ended =
      row.expected == SegmentStatus::kDone || row.expected == SegmentStatus::kTimedOut;
  EXPECT_EQ(runner.active(), row.issued && !ended);
}

INSTANTIATE_TEST_SUITE_P(
    SegmentRunner, Poll,
    ::testing::Values(
        PollRow{"nothing_issued", false, 0, true, 1.5, SegmentStatus::kIdle},
        PollRow{"running", true, 0, false, 1.5, SegmentStatus::kRunning},
        PollRow{"done", true, 0, true, 1.5, SegmentStatus::kDone},
        PollRow{"another_segments_done_flag", true, -1, true, 1.5, SegmentStatus::kRunning},
        PollRow{"at_the_timeout", true, 0, false, kIssuedS + kTimeoutS, SegmentStatus::kRunning},
        PollRow{"past_the_timeout", true, 0, false, kIssuedS + kTimeoutS + 0.25,
                SegmentStatus::kTimedOut},
        PollRow{"done_counts_before_the_timeout", true, 0, true, kIssuedS + kTimeoutS + 0.25,
                SegmentStatus::kDone}));

TEST(SegmentRunner, IssueSendsTheMoveUnderAFreshId) {
  SegmentIds ids;
  SegmentRunner runner(kTimeoutS);
  MoveTo m = carry();
  m.segment_id = 99;  // ignored
  const Command first = runner.issue(m, 0, ids);
  const Command second = runner.issue(m, 0, ids);
  ASSERT_EQ(first.kind, CommandKind::kMoveTo);
  EXPECT_EQ(first.move_to.segment_id, 1U);
  EXPECT_EQ(second.move_to.segment_id, 2U);
  EXPECT_STREQ(second.move_to.name, "MOVE3");
  EXPECT_EQ(second.move_to.target.position_m.z, 0.3);
  EXPECT_EQ(runner.move().segment_id, 2U);
}

TEST(SegmentRunner, ResumeSendsTheSameSegmentUnderANewIdAndKeepsItsTimeout) {
  SegmentIds ids;
  SegmentRunner runner(kTimeoutS);
  const std::uint32_t old_id = runner.issue(carry(), kIssuedS, ids).move_to.segment_id;
  const Command again = runner.resume(ids);
  ASSERT_EQ(again.kind, CommandKind::kMoveTo);
  EXPECT_NE(again.move_to.segment_id, old_id);
  EXPECT_STREQ(again.move_to.name, "MOVE3");
  ArmFeedback arm;
  arm.active_segment_id = old_id;
  arm.segment_done = true;
  EXPECT_EQ(runner.poll(arm, 1.5), SegmentStatus::kRunning) << "the old id's done flag";
  arm.segment_done = false;
  EXPECT_EQ(runner.poll(arm, kIssuedS + kTimeoutS + 0.25), SegmentStatus::kTimedOut);
}

TEST(SegmentRunner, NothingToResumeWhenIdle) {
  SegmentIds ids;
  SegmentRunner runner(kTimeoutS);
  EXPECT_EQ(runner.resume(ids).kind, CommandKind::kNone);
  runner.issue(carry(), 0, ids);
  runner.clear();
  EXPECT_EQ(runner.resume(ids).kind, CommandKind::kNone);
  EXPECT_FALSE(runner.active());
}

TEST(SegmentRunner, CarriesTheObjectOnlyOnARunningSegmentThatKeepsTheFingers) {
  SegmentIds ids;
  SegmentRunner runner(kTimeoutS);
  EXPECT_FALSE(runner.carries_object());
  runner.issue(carry(), 0, ids);
  EXPECT_TRUE(runner.carries_object());
  runner.clear();
  EXPECT_FALSE(runner.carries_object());
  MoveTo travel = carry();
  travel.keep_finger_velocities = false;
  runner.issue(travel, 0, ids);
  EXPECT_FALSE(runner.carries_object());
}

}  // namespace
}  // namespace tactile::control
