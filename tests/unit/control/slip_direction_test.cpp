// Slip direction analysis (paper sections III and IV.b): which element gives the direction, and
// how its sign along the gravity axis classifies grasp and release.
#include "tactile/control/slip_direction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "tactile/control/flag_analyzer.hpp"

namespace tactile::control {
namespace {

struct Elem {
  std::uint32_t id;
  double fz;
  double dx;
  double dy;
};

struct DirectionRow {
  const char* name;
  std::vector<Elem> tip0;
  std::vector<Elem> tip1;
  Vec3 gravity;
  double deadband_mm;
  SlipClass expected;
  std::int8_t fingertip;  // of the reference element (kNoFingertip for none)
  std::uint32_t element_id;
};
// gtest prints a row by its name.
void PrintTo(const DirectionRow& row, std::ostream* os) {
  *os << row.name;
}

std::vector<ElementReading> readings(const std::vector<Elem>& elems) {
  std::vector<ElementReading> out;
  for (const Elem& e : elems) {
    ElementReading r;
    r.id = e.id;
    r.contact = true;
    r.has_displacement = true;
    r.fz = e.fz;
    r.dx_mm = e.dx;
    r.dy_mm = e.dy;
    out.push_back(r);
  }
  return out;
}

class Direction : public ::testing::TestWithParam<DirectionRow> {};

TEST_P(Direction, Classification) {
  const DirectionRow& row = GetParam();
  const Config cfg;
  const std::vector<ElementReading> r0 = readings(row.tip0);
  const std::vector<ElementReading> r1 = readings(row.tip1);
  std::array<FingertipInput, kFingertips> in{};
  in[0].elements = r0;
  in[1].elements = r1;
  in[0].fresh = in[1].fresh = true;
  const Flags flags = FlagAnalyzer(cfg).analyze(in, FingerMode::kMove, false);
  const SlipDirection d = analyze_slip_direction(in, flags, row.gravity, row.deadband_mm);
  EXPECT_EQ(d.classification, row.expected) << to_string(d.classification);
  if (row.fingertip != kNoFingertip) {
    EXPECT_EQ(d.fingertip, row.fingertip);
    EXPECT_EQ(d.element_id, row.element_id);
  }
}

constexpr Vec3 kDown{0, 1, 0};  // the default: y_f is down

INSTANTIATE_TEST_SUITE_P(
    PaperRules, Direction,
    ::testing::Values(
        // The sign along gravity: positive is a grasp (weight), negative a release (contact).
        DirectionRow{"along_gravity", {{1, 0.8, 0, 0.01}}, {}, kDown, 0, SlipClass::kGrasp, 0, 1},
        DirectionRow{
            "against_gravity", {{1, 0.8, 0, -0.01}}, {}, kDown, 0, SlipClass::kRelease, 0, 1},
        DirectionRow{"mostly_sideways_still_signed",
                     {{1, 0.8, 0.02, 0.001}},
                     {},
                     kDown,
                     0,
                     SlipClass::kGrasp,
                     0,
                     1},
        DirectionRow{"purely_sideways",
                     {{1, 0.8, 0.02, 0}},
                     {},
                     kDown,
                     0,
                     SlipClass::kNone,
                     kNoFingertip,
                     0},
        DirectionRow{
            "no_slip", {{1, 0.8, 0, 0.003}}, {}, kDown, 0, SlipClass::kNone, kNoFingertip, 0},
        // Among the slipping elements, the one with the largest normal force decides: not the
        // largest displacement, not the largest force overall.
        DirectionRow{"largest_force_among_slipping",
                     {{1, 0.9, 0, -0.006}, {2, 0.4, 0, 0.05}, {3, 0.6, 0, 0.02}},
                     {},
                     kDown,
                     0,
                     SlipClass::kRelease,
                     0,
                     1},
        DirectionRow{"heavier_element_not_slipping",
                     {{1, 2.0, 0, -0.001}, {2, 0.7, 0, 0.01}},
                     {},
                     kDown,
                     0,
                     SlipClass::kGrasp,
                     0,
                     2},
        DirectionRow{"across_fingertips",
                     {{1, 0.7, 0, 0.01}},
                     {{7, 1.1, 0, -0.01}},
                     kDown,
                     0,
                     SlipClass::kRelease,
                     1,
                     7},
        DirectionRow{"across_fingertips_other_way",
                     {{1, 1.3, 0, 0.01}},
                     {{7, 1.1, 0, -0.01}},
                     kDown,
                     0,
                     SlipClass::kGrasp,
                     0,
                     1},
        // The gravity axis is configuration.
        DirectionRow{"axis_up", {{1, 0.8, 0, 0.01}}, {}, {0, -1, 0}, 0, SlipClass::kRelease, 0, 1},
        DirectionRow{
            "axis_x", {{1, 0.8, -0.01, 0.002}}, {}, {1, 0, 0}, 0, SlipClass::kRelease, 0, 1},
        DirectionRow{
            "axis_tilted", {{1, 0.8, 0.01, -0.002}}, {}, {0.6, 0.8, 0}, 0, SlipClass::kGrasp, 0, 1},
        // The dead band (0 by default, the paper's rule).
        DirectionRow{"inside_deadband",
                     {{1, 0.8, 0.02, 0.001}},
                     {},
                     kDown,
                     0.002,
                     SlipClass::kNone,
                     kNoFingertip,
                     0},
        DirectionRow{"outside_deadband",
                     {{1, 0.8, 0.02, -0.003}},
                     {},
                     kDown,
                     0.002,
                     SlipClass::kRelease,
                     0,
                     1}),
    [](const ::testing::TestParamInfo<DirectionRow>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(SlipDirection, ReportsTheReferenceElement) {
  const Config cfg;
  const std::vector<ElementReading> r0 = readings({{4, 0.3, 0, 0.01}, {5, 0.95, 0.001, 0.008}});
  std::array<FingertipInput, kFingertips> in{};
  in[0].elements = r0;
  in[0].fresh = true;
  const Flags flags = FlagAnalyzer(cfg).analyze(in, FingerMode::kMove, false);
  const SlipDirection d = analyze_slip_direction(in, flags, cfg.gravity_axis, 0);
  EXPECT_EQ(d.classification, SlipClass::kGrasp);
  EXPECT_EQ(d.index, 1);
  EXPECT_EQ(d.element_id, 5U);
  EXPECT_DOUBLE_EQ(d.fz_n, 0.95);
  EXPECT_DOUBLE_EQ(d.along_gravity_mm, 0.008);
}

TEST(SlipDirection, AFrameSeenBeforeClassifiesNothing) {
  const Config cfg;
  const std::vector<ElementReading> r0 = readings({{1, 0.8, 0, -0.02}});
  std::array<FingertipInput, kFingertips> in{};
  in[0].elements = r0;
  in[0].fresh = false;
  const Flags flags = FlagAnalyzer(cfg).analyze(in, FingerMode::kMove, false);
  EXPECT_EQ(analyze_slip_direction(in, flags, cfg.gravity_axis, 0).classification,
            SlipClass::kNone);
}

// The twist torque about +z_w: each fingertip's shear along x_f times its distance from the axis,
// with the sign of what the fingertips apply to the cap (x_f is -y_w on the left, +y_w on the
// right; a reading's F is the feeler's, the cap receives -F).
TEST(TwistTorque, IsTheMomentOfTheShearAlongXf) {
  std::vector<ElementReading> left(3);
  std::vector<ElementReading> right(2);
  for (ElementReading& r : left) {
    r.contact = true;
    r.fx = 0.1;
    r.fy = 5.0;  // vertical: no moment about z_w
    r.fz = 1.0;  // toward the axis: none either
  }
  for (ElementReading& r : right) {
    r.contact = true;
    r.fx = 0.2;
  }
  left[2].contact = false;  // out of contact: not counted
  std::array<FingertipInput, kFingertips> in{};
  in[0].elements = left;
  in[1].elements = right;
  ArmFeedback arm;
  arm.fingertip_position_m = {Vec3{-0.015, 0.001, 0.0}, Vec3{0.012, 0.0, 0.002}};
  EXPECT_NEAR(twist_torque_nm(in, arm), -(0.015 * 0.2 + 0.012 * 0.4), 1e-15);

  arm.fingertip_position_m[1].x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(twist_torque_nm(in, arm), 0.0);
  left[0].fx = std::numeric_limits<double>::infinity();  // an element's non-finite force: skipped
  arm.fingertip_position_m[1].x = 0.012;
  EXPECT_TRUE(std::isfinite(twist_torque_nm(in, arm)));
}

}  // namespace
}  // namespace tactile::control
