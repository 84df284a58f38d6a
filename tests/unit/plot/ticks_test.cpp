// Tick placement: nice steps (1, 2 or 5 times a power of ten), ticks inside the range, a
// sensible count, exact multiples, and tick text.
#include "tactile/plot/ticks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace tactile::plot {
namespace {

// The step is 1, 2 or 5 times a power of ten.
bool nice_step(double step) {
  const double mag = std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  const double m = step / mag;
  return std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9;
}

TEST(LinearTicks, UnitRange) {
  const auto t = linear_ticks(0, 1, 6);
  ASSERT_EQ(t.size(), 6U);
  for (std::size_t i = 0; i < t.size(); ++i)
    EXPECT_DOUBLE_EQ(t[i], 0.2 * static_cast<double>(i));
}

TEST(LinearTicks, KnownCases) {
  EXPECT_EQ(linear_ticks(0, 100, 5), (std::vector<double>{0, 20, 40, 60, 80, 100}));
  EXPECT_EQ(linear_ticks(-3.7, 12.2, 4), (std::vector<double>{0, 5, 10}));
  EXPECT_EQ(linear_ticks(0.13, 0.87, 4), (std::vector<double>{0.2, 0.4, 0.6, 0.8}));
  EXPECT_EQ(linear_ticks(-1, 1, 4), (std::vector<double>{-1, -0.5, 0, 0.5, 1}));
}

TEST(LinearTicks, ZeroIsExactlyZero) {
  // 0.1 * 3 - 0.3 is not 0 in binary; the tick at zero must be.
  const auto t = linear_ticks(-0.3, 0.3, 6);
  bool has_zero = false;
  for (double v : t) {
    if (v == 0) has_zero = true;
    EXPECT_FALSE(v != 0 && std::abs(v) < 1e-12) << v;
  }
  EXPECT_TRUE(has_zero);
}

TEST(LinearTicks, RandomRangesGiveNiceTicksInside) {
  // A fixed-seed sweep over magnitudes, offsets and targets.
  std::uint64_t state = 12345;
  const auto next = [&] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  for (int i = 0; i < 5000; ++i) {
    const double scale = std::pow(10.0, -6 + 12 * next());
    const double lo = (next() * 2 - 1) * scale * 10;
    const double hi = lo + scale * (0.01 + 10 * next());
    const int target = 2 + static_cast<int>(next() * 10);
    const double step = linear_tick_step(lo, hi, target);
    const auto t = linear_ticks(lo, hi, target);
    ASSERT_GT(step, 0);
    EXPECT_TRUE(nice_step(step)) << step;
    ASSERT_GE(t.size(), 2U) << lo << " " << hi;
    EXPECT_LE(t.size(), static_cast<std::size_t>(2 * target + 3)) << lo << " " << hi;
    for (std::size_t k = 0; k < t.size(); ++k) {
      EXPECT_GE(t[k], lo - step * 1e-6);
      EXPECT_LE(t[k], hi + step * 1e-6);
      // Every tick is a whole multiple of the step.
      EXPECT_NEAR(t[k] / step, std::round(t[k] / step), 1e-6);
      if (k > 0) {
        EXPECT_NEAR(t[k] - t[k - 1], step, step * 1e-6);
      }
    }
  }
}

TEST(LinearTicks, DegenerateRangesGiveNothing) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(linear_ticks(1, 1).empty());
  EXPECT_TRUE(linear_ticks(nan, 1).empty());
  EXPECT_TRUE(linear_ticks(0, inf).empty());
  EXPECT_EQ(linear_tick_step(2, 2), 0.0);
  // Reversed bounds are the same range.
  EXPECT_EQ(linear_ticks(10, 0, 5), linear_ticks(0, 10, 5));
}

TEST(LogTicks, Decades) {
  EXPECT_EQ(log_ticks(1e-3, 10), (std::vector<double>{1e-3, 1e-2, 1e-1, 1, 10}));
  EXPECT_EQ(log_ticks(0.5, 2000), (std::vector<double>{1, 10, 100, 1000}));
}

TEST(LogTicks, FewDecadesAddTwoAndFive) {
  EXPECT_EQ(log_ticks(2, 30), (std::vector<double>{2, 5, 10, 20}));
  EXPECT_EQ(log_ticks(0.8, 60), (std::vector<double>{1, 2, 5, 10, 20, 50}));
}

TEST(LogTicks, NarrowRangeFallsBackToLinear) {
  const auto t = log_ticks(3, 4);
  ASSERT_GE(t.size(), 2U);
  for (double v : t) {
    EXPECT_GE(v, 3);
    EXPECT_LE(v, 4);
  }
}

TEST(LogTicks, ManyDecadesThinOut) {
  const auto t = log_ticks(1e-20, 1e20);
  ASSERT_GE(t.size(), 5U);
  EXPECT_LE(t.size(), 11U);
  for (std::size_t k = 1; k < t.size(); ++k) {
    // Equal steps in log space, a whole number of decades each.
    const double decades = std::log10(t[k] / t[k - 1]);
    EXPECT_NEAR(decades, std::round(decades), 1e-9);
    EXPECT_NEAR(decades, std::log10(t[1] / t[0]), 1e-9);
  }
}

TEST(LogTicks, EveryTickIsOneTwoOrFiveTimesAPowerOfTen) {
  for (double lo : {1e-6, 0.03, 0.7, 4.0, 90.0}) {
    for (double span : {1.5, 8.0, 30.0, 1e3, 1e6}) {
      const auto t = log_ticks(lo, lo * span);
      ASSERT_GE(t.size(), 2U) << lo << " x" << span;
      for (double v : t) {
        EXPECT_GE(v, lo * (1 - 1e-9));
        EXPECT_LE(v, lo * span * (1 + 1e-9));
        if (span >= 8) {
          EXPECT_TRUE(nice_step(v)) << v;
        }
      }
    }
  }
}

TEST(LogTicks, NonPositiveGivesNothing) {
  EXPECT_TRUE(log_ticks(0, 10).empty());
  EXPECT_TRUE(log_ticks(-1, 10).empty());
}

TEST(FormatTick, DecimalsFollowTheStep) {
  EXPECT_EQ(format_tick(0.30000000000000004, 0.1), "0.3");
  EXPECT_EQ(format_tick(2, 0.5), "2");
  EXPECT_EQ(format_tick(2.5, 0.5), "2.5");
  EXPECT_EQ(format_tick(1500, 500), "1500");
  EXPECT_EQ(format_tick(0.025, 0.005), "0.025");
  EXPECT_EQ(format_tick(-0.0, 1), "0");
  EXPECT_EQ(format_tick(1e-17, 0.1), "0");
}

TEST(FormatTick, LargeAndSmallInScientificForm) {
  EXPECT_EQ(format_tick(150000, 50000), "1.5e5");
  EXPECT_EQ(format_tick(2e-5, 1e-5), "2e-5");
  EXPECT_EQ(format_tick(1e-4), "1e-4");
  EXPECT_EQ(format_tick(1e6), "1e6");
  EXPECT_EQ(format_tick(0.01), "0.01");
  EXPECT_EQ(format_tick(20), "20");
}

}  // namespace
}  // namespace tactile::plot
