// The rig's latency histogram: a machine's pause tens of milliseconds long must not set the x
// axis (as it did: the bulk near 1 ms was a flat line at the bottom of a 0..31 ms axis).
#include "tactile/rig/plots.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace tactile::rig {
namespace {

TEST(LatencyFigure, TwoLongPausesAreCountedAtTheEdgeAndTheBulkFillsTheAxis) {
  // 68 answers between 0.6 and 2.3 ms and two pauses of 30 and 31 ms: 70 samples, so p99 is a
  // pause (as on a demo run of this machine).
  std::vector<double> ms;
  for (int i = 0; i < 68; ++i)
    ms.push_back(0.6 + 1.7 * i / 67.0);
  ms.push_back(30.0);
  ms.push_back(31.1);
  const auto layout = latency_figure(ms).layout();
  ASSERT_EQ(layout.size(), 1U);
  EXPECT_LE(layout[0].x_lo, 0.6);
  EXPECT_GE(layout[0].x_hi, 2.3);
  // The bulk spans most of the axis, not a sliver at its left.
  EXPECT_LT(layout[0].x_hi, 5.0);
}

TEST(LatencyFigure, WithoutOutliersEveryAnswerIsOnTheAxis) {
  std::vector<double> ms;
  for (int i = 0; i < 200; ++i)
    ms.push_back(0.5 + 0.01 * i);
  const auto layout = latency_figure(ms).layout();
  ASSERT_EQ(layout.size(), 1U);
  EXPECT_LE(layout[0].x_lo, 0.5);
  EXPECT_GE(layout[0].x_hi, 2.49);
}

}  // namespace
}  // namespace tactile::rig
