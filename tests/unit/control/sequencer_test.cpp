// The skeleton both sequencers run on: events in the current step and cycle, ABORTED on a
// segment or search timeout, the finger mode that follows from what the step runs, resume.
#include "tactile/control/sequencer.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <ostream>
#include <string>

namespace tactile::control {
namespace {

MoveTo segment(bool carries) {
  return MoveTo{0, "SEG", {{0, 0, 0.2}, 0}, 0.1, 1.0, carries};
}

// A sequencer and what one update of it sees and produces.
struct Bench {
  Config cfg;
  Sequencer seq{cfg};
  SegmentIds ids;
  std::array<FingertipInput, kFingertips> tips{};
  Flags flags;
  ArmFeedback arm;
  EventList events;
  StepOutput out{Command::none(), events, FingerMode::kOff};

  StepInput at(double t) const { return StepInput{tips, flags, arm, t}; }
  void next_update() {
    events.clear();
    out.command = Command::none();
  }
};

TEST(Sequencer, EventsCarryTheStepAndTheCycle) {
  Bench b;
  b.seq.enter(Phase::kTwistApproach, b.out);
  b.seq.next_cycle();
  b.seq.enter(Phase::kTwistTurn, b.out);
  Event e;
  e.kind = EventKind::kCapTight;
  e.fingertip = 1;
  b.seq.event(e, b.out);
  ASSERT_EQ(b.events.size(), 3U);
  EXPECT_EQ(b.events[0].kind, EventKind::kPhase);
  EXPECT_STREQ(b.events[0].text, "TWIST_APPROACH");
  EXPECT_EQ(b.events[0].cycle, 0U);
  EXPECT_EQ(b.events[1].phase, Phase::kTwistTurn);
  EXPECT_EQ(b.events[1].cycle, 1U);
  EXPECT_EQ(b.events[2].phase, Phase::kTwistTurn);
  EXPECT_EQ(b.events[2].cycle, 1U);
  EXPECT_EQ(b.events[2].fingertip, 1);
  b.seq.restart();
  EXPECT_EQ(b.seq.cycle(), 0U);
  EXPECT_EQ(b.seq.phase(), Phase::kIdle);
}

TEST(Sequencer, SegmentTimeoutAborts) {
  Bench b;
  b.seq.enter(Phase::kApproach, b.out);
  b.seq.move(segment(false), 0, b.ids, b.out);
  EXPECT_EQ(b.out.command.kind, CommandKind::kMoveTo);
  b.next_update();
  EXPECT_FALSE(b.seq.segment_done(b.at(b.cfg.segment_timeout_s), b.out));
  EXPECT_TRUE(b.events.empty());
  EXPECT_FALSE(b.seq.segment_done(b.at(b.cfg.segment_timeout_s + 0.5), b.out));
  ASSERT_EQ(b.events.size(), 1U);
  EXPECT_EQ(b.events[0].kind, EventKind::kAborted);
  EXPECT_EQ(b.events[0].phase, Phase::kApproach);
  EXPECT_STREQ(b.events[0].text, "segment timed out");
  EXPECT_EQ(b.out.command.kind, CommandKind::kStop);
  EXPECT_EQ(b.seq.phase(), Phase::kAborted);
}

TEST(Sequencer, SegmentDoneByItsOwnId) {
  Bench b;
  b.seq.enter(Phase::kApproach, b.out);
  b.seq.move(segment(false), 0, b.ids, b.out);
  b.arm.active_segment_id = b.out.command.move_to.segment_id;
  b.arm.segment_done = true;
  EXPECT_TRUE(b.seq.segment_done(b.at(1.0), b.out));
  EXPECT_FALSE(b.seq.segment_done(b.at(1.0), b.out)) << "once";
}

TEST(Sequencer, GraspTouchThenSettledOrSearchTimeoutAborts) {
  Bench b;
  b.seq.enter(Phase::kGrasp, b.out);
  b.seq.search(0);
  b.next_update();
  b.flags.fingertip[0].touch = b.flags.fingertip[1].touch = true;
  b.flags.fingertip[0].max_fz_n = 0.75;
  b.flags.fingertip[1].max_fz_n = 0.5;
  EXPECT_FALSE(b.seq.grasp_settled(b.at(1.0), b.out));
  ASSERT_EQ(b.events.size(), 1U);
  EXPECT_EQ(b.events[0].kind, EventKind::kTouch);
  EXPECT_EQ(b.events[0].value, 0.5);
  EXPECT_TRUE(b.seq.grasp_settled(b.at(1.0 + b.cfg.grasp_settle_s), b.out));

  Bench timeout;
  timeout.seq.enter(Phase::kTwistGrasp, timeout.out);
  timeout.seq.search(0);
  timeout.next_update();
  EXPECT_FALSE(
      timeout.seq.grasp_settled(timeout.at(timeout.cfg.search_timeout_s + 0.5), timeout.out));
  ASSERT_EQ(timeout.events.size(), 1U);
  EXPECT_EQ(timeout.events[0].kind, EventKind::kAborted);
  EXPECT_STREQ(timeout.events[0].text, "search timed out before both fingertips touched");
  EXPECT_EQ(timeout.out.command.kind, CommandKind::kStop);
}

enum class Runs { kNothing, kSearch, kSettle, kCarry, kTravel, kRelease };
struct ModeRow {
  const char* name;
  Runs runs;
  FingerMode expected;
};
void PrintTo(const ModeRow& row, std::ostream* os) {
  *os << row.name;
}

class Mode : public ::testing::TestWithParam<ModeRow> {};

TEST_P(Mode, FollowsFromWhatTheStepRuns) {
  const ModeRow& row = GetParam();
  Bench b;
  b.seq.enter(Phase::kGrasp, b.out);
  switch (row.runs) {
    case Runs::kNothing:
      break;
    case Runs::kSearch:
      b.seq.search(0);
      break;
    case Runs::kSettle:
      b.seq.search(0);
      b.flags.fingertip[0].touch = b.flags.fingertip[1].touch = true;
      b.seq.grasp_settled(b.at(0), b.out);
      break;
    case Runs::kCarry:
      b.seq.move(segment(true), 0, b.ids, b.out);
      break;
    case Runs::kTravel:
      b.seq.move(segment(false), 0, b.ids, b.out);
      break;
    case Runs::kRelease:
      b.seq.hold_then_open(b.out);
      break;
  }
  EXPECT_EQ(b.seq.finger_mode(), row.expected);
  b.seq.enter(Phase::kRelease, b.out);
  EXPECT_EQ(b.seq.finger_mode(), FingerMode::kOff) << "a new step ends what the last one ran";
}

INSTANTIATE_TEST_SUITE_P(
    Sequencer, Mode,
    ::testing::Values(ModeRow{"nothing", Runs::kNothing, FingerMode::kOff},
                      ModeRow{"search", Runs::kSearch, FingerMode::kSearch},
                      ModeRow{"settle", Runs::kSettle, FingerMode::kMove},
                      ModeRow{"segment_carrying_the_object", Runs::kCarry, FingerMode::kMove},
                      ModeRow{"segment_with_the_fingers_stopped", Runs::kTravel, FingerMode::kOff},
                      ModeRow{"release", Runs::kRelease, FingerMode::kOff}));

TEST(Sequencer, ResumeTheOpenOrTheSegment) {
  Bench b;
  EXPECT_EQ(b.seq.resume(b.ids, 0).kind, CommandKind::kNone);

  b.seq.enter(Phase::kTwistRelease, b.out);
  b.seq.open(1.0, b.out);
  const Command open = b.seq.resume(b.ids, 1.0 + 0.25);
  ASSERT_EQ(open.kind, CommandKind::kOpen);
  EXPECT_LT(open.open.distance_m, b.cfg.open_distance_m);

  b.seq.enter(Phase::kTwistReturn, b.out);
  b.seq.move(segment(false), 2.0, b.ids, b.out);
  const std::uint32_t old_id = b.out.command.move_to.segment_id;
  const Command again = b.seq.resume(b.ids, 2.5);
  ASSERT_EQ(again.kind, CommandKind::kMoveTo);
  EXPECT_NE(again.move_to.segment_id, old_id);
  EXPECT_STREQ(again.move_to.name, "SEG");
}

TEST(Sequencer, FinishEndsEverything) {
  Bench b;
  b.seq.enter(Phase::kRetract, b.out);
  b.seq.move(segment(true), 0, b.ids, b.out);
  b.seq.finish();
  EXPECT_EQ(b.seq.phase(), Phase::kDone);
  EXPECT_EQ(b.seq.finger_mode(), FingerMode::kOff);
  EXPECT_EQ(b.seq.resume(b.ids, 1.0).kind, CommandKind::kNone);
}

}  // namespace
}  // namespace tactile::control
