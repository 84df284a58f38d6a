#include "tactile/config/controller_file.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace tactile::config {
namespace {

control::Config parse(const std::string& text) {
  return parse_controller_config(parse_yaml(text, "hand.yaml")["controller"]);
}

TEST(ControllerFile, EmptySectionKeepsTheDefaults) {
  const control::Config d;
  const control::Config c = parse("controller: {}\n");
  EXPECT_EQ(c.f1_n, d.f1_n);
  EXPECT_EQ(c.dr_mm, d.dr_mm);
  EXPECT_EQ(c.ns, d.ns);
}

TEST(ControllerFile, ReadsEveryKindOfKey) {
  const control::Config c = parse(
      "controller:\n"
      "  task: grasp_move_release\n"
      "  f1_n: 0.6\n"
      "  dr_mm: 0.005\n"
      "  ns: 5\n"
      "  twist_angle_deg: 60\n"
      "  gravity_axis: [0, -1, 0]\n"
      "  tighten_clockwise: false\n"
      "  cap_x_m: 0.3\n"
      "  stale_after_s: 0.03\n"
      "  tight_torque_rise_nm: 0.004\n");
  EXPECT_EQ(c.task, control::Task::kGraspMoveRelease);
  EXPECT_DOUBLE_EQ(c.f1_n, 0.6);
  EXPECT_DOUBLE_EQ(c.dr_mm, 0.005);
  EXPECT_EQ(c.ns, 5U);
  EXPECT_NEAR(c.twist_angle_rad, std::numbers::pi / 3, 1e-12);
  EXPECT_DOUBLE_EQ(c.gravity_axis.y, -1.0);
  EXPECT_FALSE(c.tighten_clockwise);
  EXPECT_DOUBLE_EQ(c.cap_x_m, 0.3);
  EXPECT_DOUBLE_EQ(c.stale_after_s, 0.03);
  EXPECT_DOUBLE_EQ(c.tight_torque_rise_nm, 0.004);
  EXPECT_GT(controller_config_keys().size(), 30U);
}

TEST(ControllerFile, RefusesAnUnknownKeyNamingItsLineAndTheClosestKey) {
  try {
    parse("controller:\n  f1_n: 0.6\n  dr_mn: 0.005\n");
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "hand.yaml:3: unknown key 'dr_mn' in 'controller' (did you mean 'dr_mm'?)");
  }
}

struct Bad {
  const char* yaml;
  std::vector<std::string> expect;
};

class ControllerFileRefuses : public ::testing::TestWithParam<Bad> {};

TEST_P(ControllerFileRefuses, NamingFileKeyAndValue) {
  try {
    parse(GetParam().yaml);
    FAIL() << "accepted: " << GetParam().yaml;
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("hand.yaml:", 0), 0U) << what;
    for (const auto& s : GetParam().expect)
      EXPECT_NE(what.find(s), std::string::npos) << s << " not in " << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Values, ControllerFileRefuses,
    ::testing::Values(Bad{"controller:\n  f1_n: soft\n", {"controller.f1_n", "soft"}},
                      Bad{"controller:\n  f1_n: -1\n", {"f1_n", "-1"}},
                      Bad{"controller:\n  f1_n: 3\n  f2_n: 2\n", {"f2_n", "2"}},
                      Bad{"controller:\n  task: juggle\n", {"controller.task", "juggle"}},
                      Bad{"controller:\n  ns: -3\n", {"controller.ns", "-3"}},
                      Bad{"controller:\n  gravity_axis: [0, 1]\n",
                          {"controller.gravity_axis", "3 numbers"}},
                      Bad{"controller:\n  twist_angle_deg: 90\n  twist_angle_rad: 1\n",
                          {"twist_angle_deg", "not both"}},
                      Bad{"controller:\n  tight_plateau_s: 0\n", {"tight_plateau_s", "0"}},
                      Bad{"controller: 5\n", {"controller", "mapping"}}));

}  // namespace
}  // namespace tactile::config
