// The flag analyzer (paper Fig. 5), rule by rule: TOUCH, SLIP and OVER and the dr scaling of the
// twist phase.
#include "tactile/control/flag_analyzer.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace tactile::control {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

ElementReading element(double fz, double dx = 0, double dy = 0, bool contact = true,
                       bool has_displacement = true) {
  ElementReading r;
  r.contact = contact;
  r.has_displacement = has_displacement;
  r.fz = fz;
  r.dx_mm = dx;
  r.dy_mm = dy;
  return r;
}

struct FlagRow {
  const char* name;
  std::vector<ElementReading> elements;
  bool fresh;
  bool twist;
  bool touch;
  bool slip;
  bool over;
};
// gtest prints a row by its name.
void PrintTo(const FlagRow& row, std::ostream* os) {
  *os << row.name;
}

class FlagRule : public ::testing::TestWithParam<FlagRow> {};

TEST_P(FlagRule, Flags) {
  const FlagRow& row = GetParam();
  const Config cfg;  // F1 0.5 N, F2 2.5 N, dr 0.004 mm, twist factor 1.3
  const FlagAnalyzer analyzer(cfg);
  FingertipInput in;
  in.elements = row.elements;
  in.fresh = row.fresh;
  const FingertipFlags f = analyzer.analyze(in, row.twist);
  EXPECT_EQ(f.touch, row.touch);
  EXPECT_EQ(f.slip, row.slip);
  EXPECT_EQ(f.over, row.over);
}

INSTANTIATE_TEST_SUITE_P(
    PaperRules, FlagRule,
    ::testing::Values(
        FlagRow{"nothing", {element(0, 0, 0, false, false)}, true, false, false, false, false},
        FlagRow{"light_contact", {element(0.3)}, true, false, false, false, false},
        // TOUCH: some F_z > F1 (strictly).
        FlagRow{"at_f1", {element(0.5)}, true, false, false, false, false},
        FlagRow{"over_f1", {element(0.5001)}, true, false, true, false, false},
        FlagRow{"over_f1_any_element",
                {element(0.1), element(0.2), element(0.7)},
                true,
                false,
                true,
                false,
                false},
        FlagRow{"over_f1_stale_frame", {element(0.7)}, false, false, true, false, false},
        // OVER: some F_z > F2 (strictly); TOUCH with it.
        FlagRow{"at_f2", {element(2.5)}, true, false, true, false, false},
        FlagRow{"over_f2", {element(2.5001)}, true, false, true, false, true},
        FlagRow{"over_f2_with_slip", {element(2.6, 0.01, 0)}, true, false, true, true, true},
        FlagRow{"out_of_contact_force_ignored",
                {element(3.0, 0, 0, false, false)},
                true,
                false,
                false,
                false,
                false},
        // SLIP: in contact, measured displacement, fresh frame, magnitude > dr; TOUCH with it.
        FlagRow{"slip_x", {element(0.1, 0.0041, 0)}, true, false, true, true, false},
        FlagRow{"slip_negative_y", {element(0.1, 0, -0.0041)}, true, false, true, true, false},
        FlagRow{"slip_magnitude", {element(0.1, 0.003, 0.003)}, true, false, true, true, false},
        FlagRow{"at_dr", {element(0.1, 0.004, 0)}, true, false, false, false, false},
        FlagRow{"below_dr", {element(0.1, 0.002, 0.003)}, true, false, false, false, false},
        FlagRow{"frame_seen_before", {element(0.1, 0.01, 0)}, false, false, false, false, false},
        FlagRow{"no_displacement_measured",
                {element(0.1, 0.01, 0, true, false)},
                true,
                false,
                false,
                false,
                false},
        FlagRow{
            "not_in_contact", {element(0, 0.01, 0, false, true)}, true, false, false, false, false},
        FlagRow{"one_of_many_slips",
                {element(0.2), element(0.1, 0, 0.005), element(0.3)},
                true,
                false,
                true,
                true,
                false},
        // dr * 1.3 in the twist phase.
        FlagRow{
            "between_dr_and_scaled_dr", {element(0.1, 0.005, 0)}, true, false, true, true, false},
        FlagRow{"between_dr_and_scaled_dr_twist",
                {element(0.1, 0.005, 0)},
                true,
                true,
                false,
                false,
                false},
        FlagRow{"over_scaled_dr_twist", {element(0.1, 0.0053, 0)}, true, true, true, true, false},
        FlagRow{"at_scaled_dr_twist", {element(0.1, 0.0052, 0)}, true, true, false, false, false},
        // Values that cannot be trusted are ignored, not propagated.
        FlagRow{"nan_force", {element(kNaN, 0.01, 0)}, true, false, false, false, false},
        FlagRow{"infinite_force", {element(kInf)}, true, false, false, false, false},
        FlagRow{"nan_displacement", {element(3.0, kNaN, 0)}, true, false, false, false, false},
        FlagRow{"huge_displacement", {element(0.1, 1e300, 1e300)}, true, false, true, true, false}),
    [](const ::testing::TestParamInfo<FlagRow>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(FlagAnalyzer, ScaledDrFollowsTheConfiguredFactor) {
  Config cfg;
  EXPECT_DOUBLE_EQ(FlagAnalyzer(cfg).dr(false), 0.004);
  EXPECT_DOUBLE_EQ(FlagAnalyzer(cfg).dr(true), 0.004 * 1.3);
  cfg.twist_dr_factor = 2.0;
  cfg.dr_mm = 0.01;
  const FlagAnalyzer a(cfg);
  EXPECT_DOUBLE_EQ(a.dr(true), 0.02);
  const std::vector<ElementReading> e{element(0.1, 0.015, 0)};
  FingertipInput in;
  in.elements = e;
  in.fresh = true;
  EXPECT_TRUE(a.analyze(in, false).slip);
  EXPECT_FALSE(a.analyze(in, true).slip);
}

TEST(FlagAnalyzer, ThresholdsAreConfiguration) {
  Config cfg;
  cfg.f1_n = 1.0;
  cfg.f2_n = 1.5;
  const FlagAnalyzer a(cfg);
  const std::vector<ElementReading> e{element(1.2)};
  FingertipInput in;
  in.elements = e;
  EXPECT_TRUE(a.analyze(in, false).touch);
  EXPECT_FALSE(a.analyze(in, false).over);
  const std::vector<ElementReading> e2{element(0.9), element(1.6)};
  in.elements = e2;
  EXPECT_TRUE(a.analyze(in, false).over);
}

TEST(FlagAnalyzer, NamesTheLargestForceOverallAndAmongSlipping) {
  const FlagAnalyzer a{Config{}};
  const std::vector<ElementReading> e{element(0.4, 0.01, 0), element(1.2), element(0.9, 0, 0.02),
                                      element(0.2, 0.03, 0), element(5.0, 0.01, 0, false, false)};
  FingertipInput in;
  in.elements = e;
  in.fresh = true;
  const FingertipFlags f = a.analyze(in, false);
  EXPECT_EQ(f.max_fz_index, 1);  // in contact; element 4's force is ignored
  EXPECT_DOUBLE_EQ(f.max_fz_n, 1.2);
  EXPECT_DOUBLE_EQ(f.total_fz_n, 0.4 + 1.2 + 0.9 + 0.2);
  EXPECT_EQ(f.contact_elements, 4U);  // the elements the grip sums
  EXPECT_EQ(f.slip_max_fz_index, 2);
  EXPECT_EQ(f.slipping_elements, 3U);
  EXPECT_DOUBLE_EQ(f.max_slip_mm, 0.03);
}

TEST(FlagAnalyzer, NamesTheSlippingElementsByIdInInputOrder) {
  const FlagAnalyzer a{Config{}};
  std::vector<ElementReading> e{element(0.4, 0.01, 0), element(1.2), element(0.9, 0, 0.02),
                                element(0.2, 0.03, 0)};
  for (std::size_t i = 0; i < e.size(); ++i)
    e[i].id = static_cast<std::uint32_t>(30 - i);  // ids unlike the indices
  FingertipInput in;
  in.elements = e;
  in.fresh = true;
  const FingertipFlags f = a.analyze(in, false);
  ASSERT_EQ(f.slipping_elements, 3U);
  EXPECT_EQ(f.slipping_ids[0], 30U);
  EXPECT_EQ(f.slipping_ids[1], 28U);
  EXPECT_EQ(f.slipping_ids[2], 27U);
  // From a detector's decisions: only those it marked, whatever their displacement.
  FingertipSlip slip;
  slip.state[1] = ElementSlipState::kIncipient;
  const FingertipFlags g = a.analyze(in, slip);
  ASSERT_EQ(g.slipping_elements, 1U);
  EXPECT_EQ(g.slipping_ids[0], 29U);
  // More slipping elements than the ids hold: all counted, the first kMaxSlipElements named.
  std::vector<ElementReading> many(kMaxSlipElements + 5, element(0.4, 0.01, 0));
  for (std::size_t i = 0; i < many.size(); ++i)
    many[i].id = static_cast<std::uint32_t>(i + 100);
  in.elements = many;
  const FingertipFlags h = a.analyze(in, false);
  EXPECT_EQ(h.slipping_elements, kMaxSlipElements + 5);
  EXPECT_EQ(h.slipping_ids[kMaxSlipElements - 1], 100U + kMaxSlipElements - 1);
}

TEST(FlagAnalyzer, BothFingertipsAndTheModes) {
  const FlagAnalyzer a{Config{}};
  const std::vector<ElementReading> quiet{element(0.1)};
  const std::vector<ElementReading> pressed{element(2.7)};
  std::array<FingertipInput, kFingertips> in{};
  in[0].elements = quiet;
  in[1].elements = pressed;
  const Flags search = a.analyze(in, FingerMode::kSearch, false);
  EXPECT_TRUE(search.search);
  EXPECT_FALSE(search.move);
  EXPECT_FALSE(search.fingertip[0].touch);
  EXPECT_TRUE(search.fingertip[1].touch);
  EXPECT_TRUE(search.touch);  // some fingertip touches
  EXPECT_TRUE(search.over);
  EXPECT_FALSE(search.slip);
  const Flags move = a.analyze(in, FingerMode::kMove, false);
  EXPECT_FALSE(move.search);
  EXPECT_TRUE(move.move);
  const Flags off = a.analyze(in, FingerMode::kOff, false);
  EXPECT_FALSE(off.search || off.move);
}

TEST(FlagAnalyzer, ElementNormalFallsBackToTheSqueezeDirection) {
  const std::vector<ElementReading> e(4);
  const std::vector<Vec3> n{{0, 0.6, 0.8}, {0, 0, 0}, {kNaN, 0, 1}};
  FingertipInput in;
  in.elements = e;
  in.normals = n;
  const Vec3 a = element_normal(in, 0);
  EXPECT_DOUBLE_EQ(a.y, 0.6);
  EXPECT_DOUBLE_EQ(a.z, 0.8);
  for (std::int32_t i : {1, 2, 3, -1}) {  // zero, NaN, missing, no element
    const Vec3 b = element_normal(in, i);
    EXPECT_DOUBLE_EQ(b.z, 1.0) << i;
    EXPECT_DOUBLE_EQ(b.x, 0.0) << i;
    EXPECT_DOUBLE_EQ(b.y, 0.0) << i;
  }
  const std::vector<Vec3> long_normal{{0, 0, 4}};
  in.normals = long_normal;
  EXPECT_DOUBLE_EQ(element_normal(in, 0).z, 1.0);  // normalised
}

}  // namespace
}  // namespace tactile::control
