// The rig's latency histogram: a machine's pause tens of milliseconds long must not set the x
// axis (as it did: the bulk near 1 ms was a flat line at the bottom of a 0..31 ms axis).
#include "tactile/rig/plots.hpp"

#include <gtest/gtest.h>

#include <array>
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

// The shear PNGs: each fingertip fills its axes (it was drawn in about 15 % of an x axis from
// -800 to 1400 px, the panels being wide and the aspect equal), to scale, arrows cut at the edge.
TEST(ShearFigure, EachFingertipFillsItsAxesToScale) {
  std::array<Calibration, kFingertips> cals;
  for (auto& c : cals) {
    c.mm_per_px = 0.05;
    c.elements.resize(1);
    c.elements[0].radius_px = 12;
  }
  // 41 disks in a 7 x 6 grid from (140, 60) to (500, 360) px; one long arrow out of the layout.
  Snapshot snap;
  snap.label = "grasp classified";
  for (auto& tip : snap.fingertips) {
    for (std::size_t k = 0; k < tip.size(); ++k) {
      tip[k].x_px = 140 + 60.0 * static_cast<double>(k % 7);
      tip[k].y_px = 60 + 60.0 * static_cast<double>(k / 7);
      tip[k].contact = k % 3 == 0;
      tip[k].ux_mm = k == 0 ? 2.0 : 0.01;  // 40 x 40 px: 1600 px long
    }
  }
  const auto layout = shear_figure(snap, cals).layout();
  ASSERT_EQ(layout.size(), 2U);
  for (const auto& l : layout) {
    // The layout and its disks inside, the axes no more than the margin beyond them.
    EXPECT_LE(l.x_lo, 140 - 12);
    EXPECT_GE(l.x_hi, 500 + 12);
    EXPECT_LE(l.y_lo, -360 - 12);
    EXPECT_GE(l.y_hi, -60 + 12);
    EXPECT_GE(l.x_lo, 140 - 3 * 12 - 1);
    EXPECT_LE(l.x_hi, 500 + 3 * 12 + 1);
    EXPECT_GE(l.y_lo, -360 - 3 * 12 - 1);
    EXPECT_LE(l.y_hi, -60 + 3 * 12 + 1);
    // To scale: one pixel of the image as long along x as along y.
    const double ux = (l.x_hi - l.x_lo) / (l.right - 1 - l.left);
    const double uy = (l.y_hi - l.y_lo) / (l.bottom - 1 - l.top);
    EXPECT_NEAR(ux / uy, 1.0, 1e-9);
  }
}

}  // namespace
}  // namespace tactile::rig
