// The gentle release: Hold then Open, or Open at once; done after the open's nominal duration and
// open_settle_s; resumed for the distance it had left.
#include "tactile/control/gentle_release.hpp"

#include <gtest/gtest.h>

#include <ostream>

namespace tactile::control {
namespace {

// Open 0.5 m at 0.25 m/s: 2 s, then 0.5 s of settle (values exact in binary).
Config open_config() {
  Config c;
  c.open_speed_mps = 0.25;
  c.open_distance_m = 0.5;
  c.open_settle_s = 0.5;
  return c;
}

TEST(GentleRelease, HoldThenOpenOnTheNextUpdate) {
  GentleRelease release(open_config());
  EXPECT_EQ(release.hold().kind, CommandKind::kHold);
  Command c = Command::none();
  EXPECT_FALSE(release.update(1.0, c));
  ASSERT_EQ(c.kind, CommandKind::kOpen);
  EXPECT_EQ(c.open.speed_mps, 0.25);
  EXPECT_EQ(c.open.distance_m, 0.5);
  c = Command::none();
  EXPECT_FALSE(release.update(3.25, c));
  EXPECT_TRUE(release.update(3.5, c)) << "2 s of open and 0.5 s of settle from the open at 1 s";
  EXPECT_EQ(c.kind, CommandKind::kNone);
  EXPECT_FALSE(release.update(3.75, c)) << "once";
}

struct ResumeRow {
  const char* name;
  double stopped_after_s;  // task time from the open to the resume
  CommandKind expected;
  double distance_left_m;
};
void PrintTo(const ResumeRow& row, std::ostream* os) {
  *os << row.name;
}

class Resume : public ::testing::TestWithParam<ResumeRow> {};

TEST_P(Resume, OnlyTheDistanceLeft) {
  const ResumeRow& row = GetParam();
  GentleRelease release(open_config());
  release.open(1.0);
  const Command c = release.resume(1.0 + row.stopped_after_s);
  EXPECT_EQ(c.kind, row.expected);
  if (c.kind == CommandKind::kOpen) {
    EXPECT_EQ(c.open.speed_mps, 0.25);
    EXPECT_EQ(c.open.distance_m, row.distance_left_m);
  }
}

INSTANTIATE_TEST_SUITE_P(GentleRelease, Resume,
                         ::testing::Values(ResumeRow{"at_once", 0.0, CommandKind::kOpen, 0.5},
                                           ResumeRow{"half_way", 1.0, CommandKind::kOpen, 0.25},
                                           ResumeRow{"stroke_finished", 2.0, CommandKind::kNone, 0},
                                           ResumeRow{"settling", 2.25, CommandKind::kNone, 0},
                                           ResumeRow{"clock_behind_counts_as_at_once", -1.0,
                                                     CommandKind::kOpen, 0.5}));

TEST(GentleRelease, NothingToResumeUnlessOpening) {
  GentleRelease release(open_config());
  EXPECT_EQ(release.resume(0).kind, CommandKind::kNone);
  release.hold();
  EXPECT_EQ(release.resume(0).kind, CommandKind::kNone) << "the open has not been sent";
  release.open(0);
  release.clear();
  EXPECT_EQ(release.resume(0).kind, CommandKind::kNone);
  Command c = Command::none();
  EXPECT_FALSE(release.update(10.0, c));
  EXPECT_EQ(c.kind, CommandKind::kNone);
}

}  // namespace
}  // namespace tactile::control
