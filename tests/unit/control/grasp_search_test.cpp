// The grasp of both phases: SEARCH until TOUCH on both fingertips (latched), the settle, the
// search timeout, and the finger mode of each stage.
#include "tactile/control/grasp_search.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <ostream>
#include <string>

namespace tactile::control {
namespace {

constexpr double kStepS = 0.25;
constexpr double kTimeoutS = 1.0;

Flags touching(bool left, bool right) {
  Flags f;
  f.fingertip[0].touch = left;
  f.fingertip[1].touch = right;
  return f;
}

// One update per token of `touches` ("L-": the left fingertip touches, "-R" the right, "LR"
// both, "--" neither) at kStepS, 2 kStepS, ... after the search started at 0; after the script,
// its last token again. The update each came in, -1: never.
struct SearchRow {
  const char* name;
  double settle_s;
  std::string touches;
  int touch_at;
  int settled_at;
  int timed_out_at;
};
void PrintTo(const SearchRow& row, std::ostream* os) {
  *os << row.name;
}

Flags token(const std::string& script, int k) {
  const std::size_t last = script.size() / 3;
  const std::size_t at = 3 * std::min<std::size_t>(static_cast<std::size_t>(k), last);
  return touching(script[at] == 'L', script[at + 1] == 'R');
}

class Search : public ::testing::TestWithParam<SearchRow> {};

TEST_P(Search, TouchSettleAndTimeout) {
  const SearchRow& row = GetParam();
  GraspSearch grasp(kTimeoutS, row.settle_s, 1.0);
  grasp.start(0);
  int touch_at = -1;
  int settled_at = -1;
  int timed_out_at = -1;
  for (int k = 0; k < 12; ++k) {
    const GraspProgress p = grasp.update(token(row.touches, k), (k + 1) * kStepS);
    if (p.touch) touch_at = k;
    if (p.settled) settled_at = k;
    if (p.timed_out) timed_out_at = k;
  }
  EXPECT_EQ(touch_at, row.touch_at);
  EXPECT_EQ(settled_at, row.settled_at);
  EXPECT_EQ(timed_out_at, row.timed_out_at);
}

INSTANTIATE_TEST_SUITE_P(
    GraspSearch, Search,
    ::testing::Values(SearchRow{"both_at_once", 0.5, "-- LR", 1, 3, -1},
                      SearchRow{"each_latched_until_the_other", 0.5, "L- -- -R", 2, 4, -1},
                      SearchRow{"one_alone_times_out", 0.5, "L-", -1, -1, 4},
                      SearchRow{"at_the_timeout_still_searching", 0.5, "-- -- -- -- LR", 4, 6, -1},
                      SearchRow{"settle_counts_from_the_touch_inclusive", 0.25, "LR", 0, 1, -1},
                      SearchRow{"no_settle_touch_and_settled_in_one_update", 0.0, "LR", 0, 0, -1},
                      SearchRow{"touch_relaxing_while_settling", 0.5, "LR --", 0, 2, -1}));

TEST(GraspSearch, FingerModeOfEachStage) {
  GraspSearch grasp(kTimeoutS, 0.5, 1.0);
  EXPECT_EQ(grasp.finger_mode(), FingerMode::kOff);
  grasp.start(0);
  EXPECT_EQ(grasp.finger_mode(), FingerMode::kSearch);
  grasp.update(touching(true, true), 0.25);
  EXPECT_EQ(grasp.finger_mode(), FingerMode::kMove);
  grasp.update(touching(true, true), 0.75);
  EXPECT_EQ(grasp.finger_mode(), FingerMode::kOff);
  grasp.start(1.0);
  grasp.clear();
  EXPECT_EQ(grasp.finger_mode(), FingerMode::kOff);
}

TEST(GraspSearch, ANewSearchForgetsTheTouches) {
  GraspSearch grasp(kTimeoutS, 0.5, 1.0);
  grasp.start(0);
  grasp.update(touching(true, false), 0.25);
  grasp.start(1.0);
  EXPECT_FALSE(grasp.update(touching(false, true), 1.25).touch);
  EXPECT_TRUE(grasp.update(touching(true, false), 1.5).touch);
}

// The margin grip's grasp: the settle ends when the grip has reached its target, and at the
// latest reach_timeout_s after grasp_settle_s; the paper's grip is always ready.
TEST(GraspSearch, TheSettleWaitsForTheGripUpToTheReachTimeout) {
  struct Case {
    const char* what;
    double ready_from_s;  // the grip is ready from this time on
    double settled_at_s;
  };
  const Case cases[] = {{"ready at the touch: the settle alone", 0.0, 0.75},
                        {"ready later: then", 1.25, 1.25},
                        {"never ready: the settle plus the reach timeout", 99.0, 1.75}};
  for (const Case& c : cases) {
    GraspSearch grasp(kTimeoutS, 0.5, 1.0);
    grasp.start(0);
    double settled_at = -1;
    for (int k = 1; k <= 12 && settled_at < 0; ++k) {
      const double t = k * kStepS;
      if (grasp.update(touching(true, true), t, t >= c.ready_from_s).settled) settled_at = t;
    }
    EXPECT_EQ(settled_at, c.settled_at_s) << c.what;
  }
}

TEST(GraspSearch, IdleUpdatesDoNothing) {
  GraspSearch grasp(kTimeoutS, 0.5, 1.0);
  const GraspProgress p = grasp.update(touching(true, true), 10.0);
  EXPECT_FALSE(p.touch || p.settled || p.timed_out);
}

TEST(GraspSearch, GraspForceIsTheWeakerFingertipsLargestFz) {
  Flags f;
  f.fingertip[0].max_fz_n = 0.75;
  f.fingertip[1].max_fz_n = 0.5;
  EXPECT_EQ(grasp_force(f), 0.5);
  f.fingertip[1].max_fz_n = 1.5;
  EXPECT_EQ(grasp_force(f), 0.75);
}

}  // namespace
}  // namespace tactile::control
