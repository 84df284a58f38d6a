#include "tactile/util/text.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using tactile::util::closest_match;
using tactile::util::edit_distance;

TEST(EditDistance, CountsEachInsertionDeletionSubstitutionAndSwapOnce) {
  struct Case {
    const char* a;
    const char* b;
    std::size_t distance;
  };
  const Case cases[] = {
      {"", "", 0},
      {"", "abc", 3},
      {"abc", "", 3},
      {"publish", "publish", 0},
      {"slip_tresh", "slip_thresh", 1},  // insertion
      {"publissh", "publish", 1},        // deletion
      {"f1_m", "f1_n", 1},               // substitution
      {"amr", "arm", 1},                 // swap of neighbours
      {"fsp", "fps", 1},
      {"kitten", "sitting", 3},
      {"ca", "abc", 3},  // optimal string alignment, not the unrestricted Damerau distance
  };
  for (const Case& c : cases) {
    EXPECT_EQ(edit_distance(c.a, c.b), c.distance) << c.a << " -> " << c.b;
    EXPECT_EQ(edit_distance(c.b, c.a), c.distance) << c.b << " -> " << c.a;
  }
}

TEST(ClosestMatch, NamesTheNearestCandidateWhenItIsLikelyATypo) {
  const std::vector<std::string> keys{"format",     "publish", "stats_period_s",
                                      "raw_frames", "cameras", "realtime"};
  EXPECT_EQ(closest_match("publsh", keys), "publish");
  EXPECT_EQ(closest_match("camera", keys), "cameras");
  EXPECT_EQ(closest_match("real_time", keys), "realtime");
  EXPECT_EQ(closest_match("stats_period", keys), "stats_period_s");
  EXPECT_EQ(closest_match("raw_frame", keys), "raw_frames");
}

TEST(ClosestMatch, NamesAKeyTheWordShortensWhenNoneIsNear) {
  EXPECT_EQ(closest_match("lock", {"priority", "lock_memory"}), "lock_memory");
  EXPECT_EQ(closest_match("spot", {"mm_per_px", "spot_peak_ref", "spot_sigma_min_px"}),
            "spot_peak_ref");
  EXPECT_EQ(closest_match("lo", {"priority", "lock_memory"}), "");  // too short to mean one
}

TEST(ClosestMatch, NamesNothingForAWordFarFromEveryCandidate) {
  const std::vector<std::string> keys{"format", "publish", "cameras"};
  EXPECT_EQ(closest_match("zzzzzzzz", keys), "");
  EXPECT_EQ(closest_match("x", {"y", "ns"}), "");  // a one-letter word is near nothing
  EXPECT_EQ(closest_match("publish", {}), "");
}

TEST(ClosestMatch, PrefersTheFirstOfEquallyNearCandidates) {
  EXPECT_EQ(closest_match("f_n", {"f1_n", "f2_n"}), "f1_n");
  EXPECT_EQ(closest_match("f_n", {"f2_n", "f1_n"}), "f2_n");
}

}  // namespace
