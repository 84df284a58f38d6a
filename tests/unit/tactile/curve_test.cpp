#include "tactile/curve.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace tactile {
namespace {

const PiecewiseLinear kNormal({0, 2000, 8000, 20000}, {0, 0.2, 1.0, 3.0});

TEST(PiecewiseLinear, InterpolatesBetweenKnots) {
  EXPECT_DOUBLE_EQ(kNormal(0), 0.0);
  EXPECT_DOUBLE_EQ(kNormal(1000), 0.1);
  EXPECT_DOUBLE_EQ(kNormal(2000), 0.2);
  EXPECT_DOUBLE_EQ(kNormal(5000), 0.6);
  EXPECT_DOUBLE_EQ(kNormal(20000), 3.0);
}

TEST(PiecewiseLinear, ExtrapolatesWithTheLastSlope) {
  // Last segment: 2 N over 12000 gray levels.
  EXPECT_DOUBLE_EQ(kNormal(26000), 4.0);
  // Below 0 the first segment continues (only the odd extension uses negative input).
  EXPECT_DOUBLE_EQ(kNormal(-1000), -0.1);
}

TEST(PiecewiseLinear, OddExtension) {
  const PiecewiseLinear shear({0, 0.02, 0.08}, {0, 0.05, 0.4});
  EXPECT_DOUBLE_EQ(shear.odd(0.01), 0.025);
  EXPECT_DOUBLE_EQ(shear.odd(-0.01), -0.025);
  EXPECT_DOUBLE_EQ(shear.odd(-0.14), -0.75);
}

TEST(PiecewiseLinear, InverseFindsTheSmallestArgument) {
  for (double g : {0.0, 10.0, 1999.0, 2000.0, 5000.0, 19999.0, 30000.0}) {
    EXPECT_NEAR(kNormal.inverse(kNormal(g)), g, 1e-9) << g;
  }
  const PiecewiseLinear flat({0, 1, 2, 3}, {0, 1, 1, 2});
  EXPECT_DOUBLE_EQ(flat.inverse(1.0), 1.0);
  EXPECT_DOUBLE_EQ(flat.inverse(1.5), 2.5);
  EXPECT_DOUBLE_EQ(flat.inverse(-1.0), 0.0);
  const PiecewiseLinear saturating({0, 1}, {0, 0});
  EXPECT_DOUBLE_EQ(saturating.inverse(5.0), 1.0);
}

TEST(PiecewiseLinear, HugeInputsStayFinite) {
  const double big = std::numeric_limits<double>::max();
  EXPECT_TRUE(std::isfinite(kNormal(big)));
  EXPECT_TRUE(std::isfinite(kNormal(-big)));
  EXPECT_TRUE(std::isfinite(kNormal.inverse(big)));
}

TEST(PiecewiseLinear, MonotonicEverywhere) {
  double prev = kNormal(-100);
  for (double g = -100; g < 40000; g += 7.3) {
    const double v = kNormal(g);
    EXPECT_GE(v, prev);
    prev = v;
  }
}

}  // namespace
}  // namespace tactile
