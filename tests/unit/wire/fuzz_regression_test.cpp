// Inputs the wire fuzz targets (tests/fuzz/wire) found, kept as unit tests once fixed.
#include <gtest/gtest.h>

#include <cmath>

#include "synthetic.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::wire {
namespace {

// fuzz_wire_tactile_frame: a COMPLETE frame whose centroid is finite in mm but not in pixels
// (y_mm = -1.5e308 times 40 px per mm) was accepted, and the controller got y_px = -inf.
TEST(FuzzRegression, CentroidThatOverflowsInPixelsIsRefused) {
  testing::SceneOptions o;
  o.width = 96;
  o.height = 64;
  const Calibration cal = testing::grid_calibration(o, 3, 1, 30, 12);
  std::vector<ElementReading> readings(cal.elements.size());
  for (std::size_t i = 0; i < readings.size(); ++i) {
    readings[i].id = cal.elements[i].id;
    readings[i].contact = true;
    readings[i].G = 5000;
    readings[i].x_px = cal.elements[i].center_px.x;
    readings[i].y_px = cal.elements[i].center_px.y;
  }
  FrameHeader h;
  h.status = v1::FRAME_STATUS_COMPLETE;
  v1::TactileFrame msg;
  fill_tactile_frame("left", h, readings, cal.mm_per_px, msg);
  ReceivedFrame got;
  ASSERT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kOk);

  const v1::TactileFrame valid = msg;
  msg.mutable_elements(1)->set_y_mm(-1.5235992793846782e+308);  // the fuzzer's value
  EXPECT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kInvalid);
  msg = valid;
  msg.mutable_elements(2)->set_x_mm(1e308);
  EXPECT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kInvalid);
  // Large values that stay finite in pixels are still the sender's business.
  msg = valid;
  msg.mutable_elements(0)->set_x_mm(1e300);
  ASSERT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kOk);
  EXPECT_TRUE(std::isfinite(got.elements[0].x_px));
}

}  // namespace
}  // namespace tactile::wire
