// The control configuration: the documented defaults, and validate() refusing every bad field
// with a message that names it.
#include "tactile/control/config.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <ostream>
#include <stdexcept>
#include <string>

#include "tactile/control/controller.hpp"

namespace tactile::control {
namespace {

TEST(Config, DefaultsAreThePapersAndValid) {
  const Config c;
  EXPECT_NO_THROW(c.validate());
  EXPECT_DOUBLE_EQ(c.dr_mm, 0.004);
  EXPECT_DOUBLE_EQ(c.twist_dr_factor, 1.3);
  EXPECT_EQ(c.ns, 8U);
  EXPECT_EQ(c.cycle_slip_min, 1U);
  EXPECT_DOUBLE_EQ(c.f1_n, 0.5);
  EXPECT_DOUBLE_EQ(c.f2_n, 2.5);
  EXPECT_DOUBLE_EQ(c.twist_angle_rad, std::numbers::pi / 2.0);
  EXPECT_DOUBLE_EQ(c.gravity_axis.y, 1.0);
  EXPECT_DOUBLE_EQ(c.direction_deadband_mm, 0.0);
  EXPECT_EQ(c.task, Task::kGraspMoveTwist);
  // A cap that turns freely 240 degrees tightens in the third cycle of 90 degrees.
  EXPECT_EQ(static_cast<int>(std::ceil((240.0 * std::numbers::pi / 180.0) / c.twist_angle_rad)), 3);
}

struct BadField {
  const char* field;  // must appear in the message
  std::function<void(Config&)> spoil;
};
// gtest prints a row by its name.
void PrintTo(const BadField& row, std::ostream* os) {
  *os << row.field;
}

class ConfigRefuses : public ::testing::TestWithParam<BadField> {};

TEST_P(ConfigRefuses, NamingTheField) {
  Config c;
  GetParam().spoil(c);
  try {
    c.validate();
    FAIL() << "accepted a bad " << GetParam().field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(GetParam().field), std::string::npos) << e.what();
  }
  EXPECT_THROW(GraspMoveTwistController{c}, std::invalid_argument);
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

INSTANTIATE_TEST_SUITE_P(
    EveryRule, ConfigRefuses,
    ::testing::Values(
        BadField{"f1_n", [](Config& c) { c.f1_n = 0; }},
        BadField{"f1_n", [](Config& c) { c.f1_n = kNaN; }},
        BadField{"f2_n", [](Config& c) { c.f2_n = 0.4; }},
        BadField{"f2_n", [](Config& c) { c.f2_n = c.f1_n; }},
        BadField{"dr_mm", [](Config& c) { c.dr_mm = -0.004; }},
        BadField{"dr_mm", [](Config& c) { c.dr_mm = std::numeric_limits<double>::infinity(); }},
        BadField{"twist_dr_factor", [](Config& c) { c.twist_dr_factor = 0; }},
        BadField{"gravity_axis",
                 [](Config& c) {
                   c.gravity_axis = {0, 2, 0};
                 }},
        BadField{"gravity_axis.z",
                 [](Config& c) {
                   c.gravity_axis = {0, 0, 1};
                 }},
        BadField{"gravity_axis.x", [](Config& c) { c.gravity_axis.x = kNaN; }},
        BadField{"direction_deadband_mm", [](Config& c) { c.direction_deadband_mm = -1e-3; }},
        BadField{"slip_detector",
                 [](Config& c) { c.slip_detector = static_cast<SlipDetectorKind>(7); }},
        BadField{"field_partial_slip_ratio", [](Config& c) { c.field_partial_slip_ratio = 1.5; }},
        BadField{"field_edge_ratio", [](Config& c) { c.field_edge_ratio = 0; }},
        BadField{"field_drop_ratio", [](Config& c) { c.field_drop_ratio = kNaN; }},
        BadField{"field_mu_initial", [](Config& c) { c.field_mu_initial = -0.1; }},
        BadField{"field_min_fz_n", [](Config& c) { c.field_min_fz_n = -1; }},
        BadField{"field_arm_speed_mps", [](Config& c) { c.field_arm_speed_mps = -1; }},
        BadField{"field_arm_yaw_rate_rps", [](Config& c) { c.field_arm_yaw_rate_rps = kNaN; }},
        BadField{"approach_speed_mps", [](Config& c) { c.approach_speed_mps = 0; }},
        BadField{"approach_speed_mps", [](Config& c) { c.approach_speed_mps = 0.02; }},
        BadField{"recompress_gain_mps", [](Config& c) { c.recompress_gain_mps = -1; }},
        BadField{"recompress_gain_mps", [](Config& c) { c.recompress_gain_mps = 0.02; }},
        BadField{"recompress_duration_s", [](Config& c) { c.recompress_duration_s = 0; }},
        BadField{"recompress_max_f2_fraction", [](Config& c) { c.recompress_max_f2_fraction = 0; }},
        BadField{"recompress_max_f2_fraction",
                 [](Config& c) { c.recompress_max_f2_fraction = 1.5; }},
        BadField{"recompress_max_f2_fraction",
                 [](Config& c) { c.recompress_max_f2_fraction = kNaN; }},
        BadField{"backoff_speed_mps", [](Config& c) { c.backoff_speed_mps = 0; }},
        BadField{"max_finger_speed_mps", [](Config& c) { c.max_finger_speed_mps = kNaN; }},
        BadField{"cap_x_m", [](Config& c) { c.cap_x_m = kNaN; }},
        BadField{"bottle_y_m", [](Config& c) { c.bottle_y_m = kNaN; }},
        BadField{"safe_height_m", [](Config& c) { c.safe_height_m = 0.0; }},
        BadField{"carry_height_m", [](Config& c) { c.carry_height_m = 0.005; }},
        BadField{"lower_limit_m", [](Config& c) { c.lower_limit_m = 0.3; }},
        BadField{"retract_height_m", [](Config& c) { c.retract_height_m = 0; }},
        BadField{"lower_speed_mps", [](Config& c) { c.lower_speed_mps = 0; }},
        BadField{"twist_yaw_rate_rps", [](Config& c) { c.twist_yaw_rate_rps = -1; }},
        BadField{"grasp_settle_s", [](Config& c) { c.grasp_settle_s = -0.1; }},
        BadField{"open_distance_m", [](Config& c) { c.open_distance_m = 0; }},
        BadField{"open_speed_mps", [](Config& c) { c.open_speed_mps = 0; }},
        BadField{"twist_angle_rad", [](Config& c) { c.twist_angle_rad = 0; }},
        BadField{"twist_angle_rad", [](Config& c) { c.twist_angle_rad = 7.0; }},
        BadField{"ns", [](Config& c) { c.ns = 0; }},
        BadField{"cycle_slip_min", [](Config& c) { c.cycle_slip_min = 0; }},
        BadField{"max_twist_cycles", [](Config& c) { c.max_twist_cycles = 0; }},
        BadField{"tight_torque_rise_nm", [](Config& c) { c.tight_torque_rise_nm = 0; }},
        BadField{"tight_torque_rise_ratio", [](Config& c) { c.tight_torque_rise_ratio = -1; }},
        BadField{"tight_level_s", [](Config& c) { c.tight_level_s = kNaN; }},
        BadField{"tight_plateau_s", [](Config& c) { c.tight_plateau_s = 0; }},
        BadField{"tight_plateau_fraction", [](Config& c) { c.tight_plateau_fraction = 1.0; }},
        BadField{"search_timeout_s", [](Config& c) { c.search_timeout_s = 0; }},
        BadField{"segment_timeout_s", [](Config& c) { c.segment_timeout_s = kNaN; }},
        BadField{"stale_after_s", [](Config& c) { c.stale_after_s = 0; }},
        BadField{"stale_abort_s", [](Config& c) { c.stale_abort_s = -1; }},
        BadField{"task", [](Config& c) { c.task = static_cast<Task>(9); }}));

// What every run prints in its first lines: the detector and the grip, named by their to_string.
TEST(Config, DescribesItsDetectorAndGrip) {
  Config c;
  EXPECT_EQ(c.grip, GripKind::kPaper);
  EXPECT_STREQ(to_string(GripKind::kPaper), "paper");
  EXPECT_EQ(describe_controller(c), "slip detector: learned, grip: paper");
  c.slip_detector = SlipDetectorKind::kField;
  EXPECT_EQ(describe_controller(c), "slip detector: field, grip: paper");
}

TEST(Config, MessageGivesTheValue) {
  Config c;
  c.f1_n = -2.5;
  try {
    c.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("-2.5"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tactile::control
