#include "tactile/util/percentile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using tactile::util::nearest_rank_of_sorted;
using tactile::util::nearest_rank_percentile;

struct Case {
  std::vector<double> values;
  double q;
  double expected;
};

// Rank ceil(q n), at least 1, of the sorted values: never an interpolation.
TEST(NearestRankPercentile, IsTheValueAtRankCeilQN) {
  const std::vector<Case> cases{
      {{7}, 0.0, 7},
      {{7}, 0.5, 7},
      {{7}, 1.0, 7},
      {{4, 1, 3, 2}, 0.0, 1},     // rank 0 -> 1
      {{4, 1, 3, 2}, 0.25, 1},    // rank 1
      {{4, 1, 3, 2}, 0.26, 2},    // rank ceil(1.04) = 2
      {{4, 1, 3, 2}, 0.5, 2},     // the lower middle value (interpolation would give 2.5)
      {{4, 1, 3, 2}, 0.75, 3},    // rank 3
      {{4, 1, 3, 2}, 1.0, 4},     // rank 4
      {{5, 1, 4, 2, 3}, 0.5, 3},  // rank ceil(2.5) = 3
      {{5, 1, 4, 2, 3}, 0.05, 1},
      {{5, 1, 4, 2, 3}, 0.99, 5},
      {{10, 20, 30, 40, 50, 60, 70, 80, 90, 100}, 0.9, 90},
      {{10, 20, 30, 40, 50, 60, 70, 80, 90, 100}, 0.91, 100},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(nearest_rank_percentile(c.values, c.q), c.expected)
        << "q " << c.q << " of " << c.values.size() << " values";
  }
}

TEST(NearestRankPercentile, NinetyNinthOfAHundredValuesIsTheSecondLargest) {
  std::vector<double> v;
  for (int i = 100; i >= 1; --i)
    v.push_back(i);
  EXPECT_EQ(nearest_rank_percentile(v, 0.99), 99);
  EXPECT_EQ(nearest_rank_percentile(v, 0.50), 50);
  v.push_back(101);  // 101 values: rank ceil(99.99) = 100
  EXPECT_EQ(nearest_rank_percentile(v, 0.99), 100);
}

TEST(NearestRankPercentile, NoValuesGiveTheValueAskedFor) {
  EXPECT_EQ(nearest_rank_percentile({}, 0.5), 0.0);
  EXPECT_TRUE(std::isnan(nearest_rank_percentile({}, 0.5, std::nan(""))));
}

TEST(NearestRankPercentile, OfSortedValuesIsTheSame) {
  const std::vector<double> sorted{1, 2, 2, 3, 8, 9};
  for (const double q : {0.0, 0.1, 0.34, 0.5, 0.51, 0.99, 1.0})
    EXPECT_EQ(nearest_rank_of_sorted(sorted, q), nearest_rank_percentile({9, 2, 8, 1, 3, 2}, q))
        << q;
}

}  // namespace
