#include "tactile/curve.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

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

// The curve's value by its definition: the segment found by upper_bound over all knots, the
// outer segments extended.
double by_definition(const std::vector<double>& x, const std::vector<double>& y, double v) {
  if (x.size() == 1) return y[0];
  const auto it = std::upper_bound(x.begin(), x.end(), v);
  const std::size_t k =
      std::clamp<std::size_t>(static_cast<std::size_t>(it - x.begin()), 1, x.size() - 1) - 1;
  const double r = y[k] + (y[k + 1] - y[k]) / (x[k + 1] - x[k]) * (v - x[k]);
  return std::isfinite(r) ? r : (r > 0 ? y.back() : y.front());
}

TEST(PiecewiseLinear, EverySegmentOfCurvesOfEverySize) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> step(0.01, 10.0);
  for (std::size_t n = 1; n <= 40; ++n) {
    std::vector<double> x(n), y(n);
    double xs = -50, ys = 0;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = xs += step(rng);
      y[i] = ys += step(rng);
    }
    const PiecewiseLinear c(x, y);
    // Every knot exactly, both sides of it, and beyond both ends.
    std::vector<double> probes = {x.front() - 100, x.back() + 100, -1e300, 1e300};
    for (double k : x) {
      probes.push_back(k);
      probes.push_back(std::nextafter(k, -1e300));
      probes.push_back(std::nextafter(k, 1e300));
      probes.push_back(k + 0.5);
    }
    for (double v : probes) {
      const double want = by_definition(x, y, v);
      const double got = c(v);
      ASSERT_EQ(got, want) << "n " << n << " x " << v;
      ASSERT_TRUE(std::isfinite(got));
    }
  }
}

}  // namespace
}  // namespace tactile
