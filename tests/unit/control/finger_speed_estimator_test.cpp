// The finger speed estimator (paper Fig. 6): approach, stop at F1, re-compression along the
// inward normal of the element with the largest normal force, OVER first, and bounds.
#include "tactile/control/finger_speed_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "tactile/control/flag_analyzer.hpp"

namespace tactile::control {
namespace {

// Unit normals, 30 degrees off the pole and tilted along x_f.
const double kCos30 = std::sqrt(3.0) / 2.0;

// Two fingertips whose readings a test sets element by element; flags come from the real
// analyzer so that the estimator sees what the controller would give it.
class Hand {
 public:
  explicit Hand(const Config& cfg = Config{}) : cfg_(cfg), analyzer_(cfg), estimator_(cfg) {
    for (auto& tip : elements_)
      tip.resize(4);
    for (auto& tip : normals_)
      tip = {{0, 0, 1}, {0, -0.5, kCos30}, {0.6, 0, 0.8}, {-0.6, 0, 0.8}};
  }
  void press(std::size_t tip, std::size_t e, double fz) {
    elements_[tip][e].contact = fz > 0;
    elements_[tip][e].fz = fz;
  }
  void slip(std::size_t tip, std::size_t e, double dx, double dy) {
    elements_[tip][e].has_displacement = true;
    elements_[tip][e].dx_mm = dx;
    elements_[tip][e].dy_mm = dy;
  }
  void set_normal(std::size_t tip, std::size_t e, Vec3 n) { normals_[tip][e] = n; }
  // One update at time t, then the displacements are consumed (next frame is still).
  FingerSpeedOutput update(FingerMode mode, double t, bool fresh = true, GripContext grip = {}) {
    std::array<FingertipInput, kFingertips> in{};
    for (std::size_t f = 0; f < kFingertips; ++f) {
      in[f].elements = elements_[f];
      in[f].normals = normals_[f];
      in[f].fresh = fresh;
    }
    flags_ = analyzer_.analyze(in, mode, false);
    const FingerSpeedOutput out = estimator_.update(mode, flags_, in, t, grip);
    for (auto& tip : elements_) {
      for (auto& r : tip)
        r.dx_mm = r.dy_mm = 0;
    }
    return out;
  }
  FingerSpeedEstimator& estimator() { return estimator_; }
  const Config& cfg() const { return cfg_; }

 private:
  Config cfg_;
  FlagAnalyzer analyzer_;
  FingerSpeedEstimator estimator_;
  std::array<std::vector<ElementReading>, kFingertips> elements_;
  std::array<std::vector<Vec3>, kFingertips> normals_;
  Flags flags_;
};

void expect_vec(Vec3 v, Vec3 expected, const std::string& what) {
  EXPECT_NEAR(v.x, expected.x, 1e-12) << what;
  EXPECT_NEAR(v.y, expected.y, 1e-12) << what;
  EXPECT_NEAR(v.z, expected.z, 1e-12) << what;
}

TEST(FingerSpeedEstimator, SearchApproachesAlongTheSqueezeDirection) {
  Hand hand;
  const FingerSpeedOutput out = hand.update(FingerMode::kSearch, 0.0);
  for (std::size_t f = 0; f < kFingertips; ++f) {
    expect_vec(out.velocity_mps[f], {0, 0, hand.cfg().approach_speed_mps}, "approach");
    EXPECT_EQ(out.action[f], FingerAction::kApproach);
  }
}

TEST(FingerSpeedEstimator, SearchStopsEachFingertipPastF1AndHolds) {
  Hand hand;
  hand.press(0, 0, 0.3);  // touching, under F1: keep closing
  FingerSpeedOutput out = hand.update(FingerMode::kSearch, 0.00);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().approach_speed_mps);
  hand.press(0, 0, 0.51);  // past F1: stop and hold; the other fingertip keeps searching
  out = hand.update(FingerMode::kSearch, 0.01);
  expect_vec(out.velocity_mps[0], {0, 0, 0}, "stopped");
  EXPECT_EQ(out.action[0], FingerAction::kHold);
  EXPECT_DOUBLE_EQ(out.velocity_mps[1].z, hand.cfg().approach_speed_mps);
  // The force relaxes under F1: the touch is latched, the fingertip does not close again.
  hand.press(0, 0, 0.45);
  out = hand.update(FingerMode::kSearch, 0.02);
  expect_vec(out.velocity_mps[0], {0, 0, 0}, "latched");
  // A new search (after another mode) starts afresh.
  hand.update(FingerMode::kOff, 0.03);
  out = hand.update(FingerMode::kSearch, 0.04);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().approach_speed_mps);
}

TEST(FingerSpeedEstimator, SearchStopsOnSlipBelowF1) {
  Hand hand;
  hand.press(1, 0, 0.1);
  hand.slip(1, 0, 0.0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kSearch, 0.0);
  expect_vec(out.velocity_mps[1], {0, 0, 0}, "slip is touch");
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().approach_speed_mps);
}

TEST(FingerSpeedEstimator, MoveHoldsWithoutSlip) {
  Hand hand;
  hand.press(0, 0, 1.0);
  hand.press(1, 0, 1.0);
  const FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.0);
  for (std::size_t f = 0; f < kFingertips; ++f) {
    expect_vec(out.velocity_mps[f], {0, 0, 0}, "hold");
    EXPECT_EQ(out.action[f], FingerAction::kHold);
    EXPECT_FALSE(out.recompress_started[f]);
  }
}

struct RecompressRow {
  const char* name;
  std::array<double, 4> fz;  // per element
  std::size_t slipping;      // the element that slips
  Vec3 expected_direction;   // the inward normal of the largest-F_z element
};
// gtest prints a row by its name.
void PrintTo(const RecompressRow& row, std::ostream* os) {
  *os << row.name;
}

class Recompression : public ::testing::TestWithParam<RecompressRow> {};

TEST_P(Recompression, AlongTheInwardNormalOfTheLargestForce) {
  const RecompressRow& row = GetParam();
  Hand hand;
  for (std::size_t e = 0; e < 4; ++e)
    hand.press(0, e, row.fz[e]);
  hand.slip(0, row.slipping, 0.0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.0);
  EXPECT_EQ(out.action[0], FingerAction::kRecompress);
  EXPECT_TRUE(out.recompress_started[0]);
  const double gain = hand.cfg().recompress_gain_mps;
  expect_vec(out.velocity_mps[0], gain * row.expected_direction, row.name);
  // Only the slipping fingertip re-compresses.
  expect_vec(out.velocity_mps[1], {0, 0, 0}, "other fingertip");
}

INSTANTIATE_TEST_SUITE_P(
    PaperRules, Recompression,
    ::testing::Values(
        RecompressRow{"pole", {1.0, 0.3, 0.2, 0.2}, 0, {0, 0, 1}},
        RecompressRow{"upper_element", {0.4, 1.1, 0.2, 0.2}, 1, {0, -0.5, kCos30}},
        RecompressRow{"side_element", {0.4, 0.3, 0.9, 0.2}, 2, {0.6, 0, 0.8}},
        // The slipping element is not the one with the largest force: the largest force decides.
        RecompressRow{"largest_force_not_slipping", {0.4, 0.3, 0.2, 0.95}, 0, {-0.6, 0, 0.8}},
        RecompressRow{"largest_force_elsewhere", {1.2, 0.3, 0.2, 0.7}, 3, {0, 0, 1}}),
    [](const ::testing::TestParamInfo<RecompressRow>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(FingerSpeedEstimator, RecompressionAddsToTheCurrentVelocityWithinItsBound) {
  Config cfg;
  cfg.recompress_gain_mps = 0.003;
  cfg.max_finger_speed_mps = 0.008;
  Hand hand(cfg);
  hand.press(0, 0, 1.0);
  hand.slip(0, 0, 0, 0.01);
  FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.00);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, 0.003);
  hand.slip(0, 0, 0, 0.01);
  out = hand.update(FingerMode::kMove, 0.01);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, 0.006);  // added to the current one
  EXPECT_FALSE(out.recompress_started[0]);         // the same episode
  hand.slip(0, 0, 0, 0.01);
  out = hand.update(FingerMode::kMove, 0.02);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, 0.008);  // bounded
  // The direction changes to the new largest-force element: the sum keeps its bound.
  hand.press(0, 2, 1.5);
  hand.slip(0, 2, 0.01, 0);
  out = hand.update(FingerMode::kMove, 0.03);
  EXPECT_NEAR(norm(out.velocity_mps[0]), 0.008, 1e-15);
  EXPECT_GT(out.velocity_mps[0].x, 0.0);
}

TEST(FingerSpeedEstimator, RecompressionEndsAfterItsDurationWithoutSlip) {
  Hand hand;
  const double d = hand.cfg().recompress_duration_s;
  hand.press(0, 0, 1.0);
  hand.slip(0, 0, 0, 0.01);
  hand.update(FingerMode::kMove, 1.0);
  FingerSpeedOutput out = hand.update(FingerMode::kMove, 1.0 + 0.5 * d);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().recompress_gain_mps);
  EXPECT_EQ(out.action[0], FingerAction::kRecompress);
  out = hand.update(FingerMode::kMove, 1.0 + d);
  expect_vec(out.velocity_mps[0], {0, 0, 0}, "back to hold");
  EXPECT_EQ(out.action[0], FingerAction::kHold);
  // A later slip is a new episode starting from rest.
  hand.slip(0, 0, 0, 0.01);
  out = hand.update(FingerMode::kMove, 2.0);
  EXPECT_TRUE(out.recompress_started[0]);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().recompress_gain_mps);
}

TEST(FingerSpeedEstimator, AGripNearF2HoldsInsteadOfReCompressing) {
  Hand hand;
  const double limit = hand.cfg().recompress_max_f2_fraction * hand.cfg().f2_n;
  ASSERT_LT(limit, hand.cfg().f2_n);
  // Just under the limit: the paper's re-compression.
  hand.press(0, 0, limit - 0.01);
  hand.slip(0, 0, 0, 0.01);
  FingerSpeedOutput out = hand.update(FingerMode::kMove, 1.0);
  EXPECT_EQ(out.action[0], FingerAction::kRecompress);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().recompress_gain_mps);
  // The squeeze brings F_z to the limit: the re-compression under way stops there, although its
  // duration has not run out and the fingertip is still under F2.
  hand.press(0, 0, limit);
  out = hand.update(FingerMode::kMove, 1.01);
  EXPECT_EQ(out.action[0], FingerAction::kHold);
  expect_vec(out.velocity_mps[0], {0, 0, 0}, "at the limit");
  // A slip with no headroom left holds too: no new re-compression, no OVER.
  hand.slip(0, 0, 0, 0.01);
  out = hand.update(FingerMode::kMove, 1.02);
  EXPECT_EQ(out.action[0], FingerAction::kHold);
  EXPECT_FALSE(out.recompress_started[0]);
  EXPECT_FALSE(out.over_started[0]);
  // Back under the limit (the grip relaxed), a slip re-compresses again.
  hand.press(0, 0, limit - 0.2);
  hand.slip(0, 0, 0, 0.01);
  out = hand.update(FingerMode::kMove, 1.03);
  EXPECT_EQ(out.action[0], FingerAction::kRecompress);
  EXPECT_TRUE(out.recompress_started[0]);
}

TEST(FingerSpeedEstimator, AFractionOfOneIsThePapersRule) {
  Config cfg;
  cfg.recompress_max_f2_fraction = 1.0;
  Hand hand(cfg);
  hand.press(0, 0, 0.95 * cfg.f2_n);  // above the default's limit, under F2
  hand.slip(0, 0, 0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kMove, 1.0);
  EXPECT_EQ(out.action[0], FingerAction::kRecompress);
}

TEST(FingerSpeedEstimator, AFrameSeenBeforeDoesNotReCompressAgain) {
  Hand hand;
  hand.press(0, 0, 1.0);
  hand.slip(0, 0, 0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.0, /*fresh=*/false);
  expect_vec(out.velocity_mps[0], {0, 0, 0}, "not fresh");
  EXPECT_FALSE(out.recompress_started[0]);
}

struct OverRow {
  const char* name;
  FingerMode mode;
  bool slip;
};
// gtest prints a row by its name.
void PrintTo(const OverRow& row, std::ostream* os) {
  *os << row.name;
}

class OverFirst : public ::testing::TestWithParam<OverRow> {};

TEST_P(OverFirst, StopsSqueezingAndBacksOff) {
  const OverRow& row = GetParam();
  Hand hand;
  hand.press(0, 0, 2.6);  // > F2
  if (row.slip) hand.slip(0, 0, 0, 0.02);
  const FingerSpeedOutput out = hand.update(row.mode, 0.0);
  expect_vec(out.velocity_mps[0], {0, 0, -hand.cfg().backoff_speed_mps}, row.name);
  EXPECT_EQ(out.action[0], FingerAction::kBackOff);
  EXPECT_TRUE(out.over_started[0]);
  EXPECT_FALSE(out.recompress_started[0]);
}

INSTANTIATE_TEST_SUITE_P(PaperRules, OverFirst,
                         ::testing::Values(OverRow{"search", FingerMode::kSearch, false},
                                           OverRow{"search_with_slip", FingerMode::kSearch, true},
                                           OverRow{"move", FingerMode::kMove, false},
                                           OverRow{"move_with_slip", FingerMode::kMove, true}),
                         [](const ::testing::TestParamInfo<OverRow>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(FingerSpeedEstimator, OverInterruptsARecompressionAndHoldsWhenClear) {
  Hand hand;
  hand.press(0, 0, 2.0);
  hand.slip(0, 0, 0, 0.01);
  FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.0);
  EXPECT_GT(out.velocity_mps[0].z, 0.0);
  hand.press(0, 0, 2.7);
  out = hand.update(FingerMode::kMove, 0.01);
  EXPECT_LT(out.velocity_mps[0].z, 0.0);
  EXPECT_TRUE(out.over_started[0]);
  out = hand.update(FingerMode::kMove, 0.02);
  EXPECT_FALSE(out.over_started[0]);  // only the rising edge
  hand.press(0, 0, 2.4);
  out = hand.update(FingerMode::kMove, 0.03);  // under F2, within the old re-compression's time
  expect_vec(out.velocity_mps[0], {0, 0, 0}, "hold, not squeeze again");
}

TEST(FingerSpeedEstimator, OffIsStill) {
  Hand hand;
  hand.press(0, 0, 2.6);
  hand.press(1, 0, 1.0);
  hand.slip(1, 0, 0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kOff, 0.0);
  for (std::size_t f = 0; f < kFingertips; ++f) {
    expect_vec(out.velocity_mps[f], {0, 0, 0}, "off");
    EXPECT_EQ(out.action[f], FingerAction::kIdle);
  }
  EXPECT_TRUE(out.over_started[0]);  // the force still passed F2
}

TEST(FingerSpeedEstimator, ResetForgetsTheCurrentVelocity) {
  Hand hand;
  hand.press(0, 0, 1.0);
  hand.slip(0, 0, 0, 0.01);
  hand.update(FingerMode::kMove, 0.0);
  hand.estimator().reset();
  EXPECT_DOUBLE_EQ(norm(hand.estimator().velocity()[0]), 0.0);
  hand.slip(0, 0, 0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.01);
  EXPECT_DOUBLE_EQ(out.velocity_mps[0].z, hand.cfg().recompress_gain_mps);  // not 2x
  EXPECT_TRUE(out.recompress_started[0]);
}

// A stale hold stops the fingers but is not a new grasp: the margin grip keeps its target (a grip
// that started again from grip_min_n would open on the held cap once data came back); a reset,
// a new grasp, starts it again.
TEST(FingerSpeedEstimator, AStaleHoldKeepsTheMarginGripsTargetAResetDoesNot) {
  Config cfg;
  cfg.grip = GripKind::kMargin;
  cfg.grip_loading_speed_mps = 0;  // a lift without its loading phase has the floor grip_lift_n
  Hand hand(cfg);
  for (std::size_t f = 0; f < kFingertips; ++f)
    hand.press(f, 0, 0.3);
  double t = 0;
  GripContext grasp;  // the grasp before the lift: the target is grip_lift_n, above the least
  grasp.lifting = true;
  hand.update(FingerMode::kMove, t, true, grasp);
  const double raised = hand.estimator().grip_law().target_n();
  ASSERT_EQ(raised, cfg.grip_lift_n);
  hand.estimator().stop_for_stale();
  EXPECT_DOUBLE_EQ(norm(hand.estimator().velocity()[0]), 0.0);
  EXPECT_EQ(hand.estimator().grip_law().target_n(), raised);
  hand.update(FingerMode::kMove, t += 0.01, true, grasp);
  EXPECT_EQ(hand.estimator().grip_law().target_n(), raised) << "the first update after it";
  hand.estimator().reset();
  EXPECT_EQ(hand.estimator().grip_law().target_n(), cfg.grip_min_n);
}

TEST(FingerSpeedEstimator, UnusableNormalsFallBackToTheSqueezeDirection) {
  Hand hand;
  hand.set_normal(0, 0, {std::nan(""), 0, 1});
  hand.press(0, 0, 1.0);
  hand.slip(0, 0, 0, 0.01);
  const FingerSpeedOutput out = hand.update(FingerMode::kMove, 0.0);
  expect_vec(out.velocity_mps[0], {0, 0, hand.cfg().recompress_gain_mps}, "fallback");
}

TEST(BoundVelocity, KeepsDirectionAndRejectsNonFinite) {
  expect_vec(bound_velocity({0.03, 0, 0.04}, 0.01), {0.006, 0, 0.008}, "scaled");
  expect_vec(bound_velocity({0.001, 0, 0}, 0.01), {0.001, 0, 0}, "inside");
  expect_vec(bound_velocity({std::nan(""), 0, 0}, 0.01), {0, 0, 0}, "nan");
  expect_vec(bound_velocity({1e308, 1e308, 0}, 0.01), {0, 0, 0}, "overflow");
  expect_vec(bound_velocity({0.1, 0, 0}, 0.0), {0, 0, 0}, "no bound");
}

}  // namespace
}  // namespace tactile::control
