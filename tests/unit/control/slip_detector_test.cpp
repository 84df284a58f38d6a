// The slip detectors behind one interface (docs/slip.md, "The detectors"): the paper's rule as
// the flag analyzer always decided it, and the field detector's rigid-motion residual,
// friction-cone load and arm motion, each on hand-made fingertip frames.
#include "tactile/control/slip_detector.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "forest_paths.hpp"
#include "tactile/control/flag_analyzer.hpp"

namespace tactile::control {
namespace {

constexpr double kThr = 0.004;  // dr, mm per frame

// A 5 x 5 grid of elements 20 px apart, all in contact, pressed with `fz`, sheared with
// |F_t| = ratio * fz along x.
struct Tip {
  std::vector<ElementReading> r;
  FingertipInput in;
  explicit Tip(double fz = 0.5, double ratio = 0.3) {
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 5; ++col) {
        ElementReading e;
        e.id = static_cast<std::uint32_t>(r.size());
        e.contact = true;
        e.has_displacement = true;
        e.x_px = 100.0 + 20.0 * col;
        e.y_px = 100.0 + 20.0 * row;
        e.fz = fz;
        e.fx = ratio * fz;
        r.push_back(e);
      }
    }
    in.fresh = true;
    sync();
  }
  void sync() { in.elements = r; }
  void move_all(double dx, double dy) {
    for (ElementReading& e : r) {
      e.dx_mm = dx;
      e.dy_mm = dy;
    }
  }
};

Config field_config() {
  Config c;
  c.slip_detector = SlipDetectorKind::kField;
  return c;
}

std::size_t count_state(const FingertipSlip& s, std::size_t n, ElementSlipState state) {
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i)
    k += s.state[i] == state ? 1 : 0;
  return k;
}

TEST(SlipDetectorNames, RoundTripAndRefuseOthers) {
  for (auto k : {SlipDetectorKind::kPaper, SlipDetectorKind::kField})
    EXPECT_EQ(slip_detector_from_string(to_string(k)), k);
  EXPECT_FALSE(slip_detector_from_string("Paper").has_value());
  EXPECT_FALSE(slip_detector_from_string("").has_value());
}

// The paper detector is the flag analyzer's rule, element for element, on random frames with
// NaNs, frames without displacement and elements out of contact.
TEST(PaperDetector, DecidesAsTheFlagAnalyzersRule) {
  Config cfg;
  SlipDetector det(SlipDetectorKind::kPaper, cfg);
  FlagAnalyzer flags(cfg);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  std::bernoulli_distribution coin(0.5), rare(0.05);
  for (int frame = 0; frame < 2000; ++frame) {
    Tip tip;
    for (ElementReading& e : tip.r) {
      e.contact = coin(rng);
      e.has_displacement = coin(rng);
      e.dx_mm = rare(rng) ? std::numeric_limits<double>::quiet_NaN() : u(rng);
      e.dy_mm = u(rng);
      e.fz = rare(rng) ? std::numeric_limits<double>::infinity() : 0.5;
    }
    tip.in.fresh = frame % 7 != 0;
    tip.sync();
    const bool twist = frame % 3 == 0;
    const FingertipSlip& s = det.update(0, tip.in, flags.dr(twist), {});
    const FingertipFlags old = flags.analyze(tip.in, twist);
    const FingertipFlags now = flags.analyze(tip.in, s);
    ASSERT_EQ(now.slip, old.slip) << frame;
    ASSERT_EQ(now.slipping_elements, old.slipping_elements) << frame;
    ASSERT_EQ(now.slip_max_fz_index, old.slip_max_fz_index) << frame;
    ASSERT_EQ(now.touch, old.touch) << frame;
  }
}

// The whole contact moving more than dr with a load: gross slip on every element.
TEST(FieldDetector, ALoadedContactMovingAsAWholeSlips) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.3);
  tip.move_all(0.0, 0.0);
  det.update(0, tip.in, kThr, {});
  tip.move_all(0.0, 3 * kThr);
  const FingertipSlip& s = det.update(0, tip.in, kThr, {});
  EXPECT_EQ(count_state(s, tip.r.size(), ElementSlipState::kSlip), tip.r.size());
  EXPECT_EQ(s.fingertip, ElementSlipState::kSlip);
  EXPECT_NEAR(s.rigid_mm, 3 * kThr, 1e-12);
  EXPECT_NEAR(s.slip_mm[0], 3 * kThr, 1e-12);
}

// The same motion without load (far inside the friction cone, below the partial-slip ratio of the
// friction estimate) is not a slip: the paper's rule would call it one.
TEST(FieldDetector, AnUnloadedContactMovingIsNotASlip) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.01);
  det.update(0, tip.in, kThr, {});
  tip.move_all(0.0, 3 * kThr);
  const FingertipSlip& s = det.update(0, tip.in, kThr, {});
  EXPECT_EQ(s.slipping, 0U);
  EXPECT_EQ(count_state(s, tip.r.size(), ElementSlipState::kStick), tip.r.size());
}

// A rotation is a rigid motion too: fitted, it leaves no residual; the elements it carries more
// than dr slip (gross, rotational), the others stick.
TEST(FieldDetector, ARotationIsFittedAsRigid) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.3);
  det.update(0, tip.in, kThr, {});
  const double w = 0.5 * kThr / 20.0;  // mm per px: the corners move 2.8 dr, the centre 0
  for (ElementReading& e : tip.r) {
    e.dx_mm = -w * (e.y_px - 140.0);
    e.dy_mm = w * (e.x_px - 140.0);
  }
  tip.sync();
  const FingertipSlip& s = det.update(0, tip.in, kThr, {});
  EXPECT_NEAR(s.rigid_mm, 0.0, 1e-12);
  EXPECT_EQ(s.incipient, 0U);
  for (std::size_t i = 0; i < tip.r.size(); ++i) {
    const double r_px = std::hypot(tip.r[i].x_px - 140.0, tip.r[i].y_px - 140.0);
    EXPECT_EQ(s.state[i], w * r_px > kThr ? ElementSlipState::kSlip : ElementSlipState::kStick)
        << i;
  }
}

// One element left behind by a contact that sticks: incipient slip on it alone.
TEST(FieldDetector, AnElementLeavingTheRigidMotionIsIncipient) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.3);
  det.update(0, tip.in, kThr, {});
  tip.move_all(0.0, 0.2 * kThr);
  tip.r[0].dy_mm = -2.5 * kThr;
  tip.sync();
  const FingertipSlip& s = det.update(0, tip.in, kThr, {});
  EXPECT_EQ(s.state[0], ElementSlipState::kIncipient);
  EXPECT_EQ(s.incipient, 1U);
  EXPECT_EQ(s.slipping, 1U);
  EXPECT_EQ(s.fingertip, ElementSlipState::kIncipient);
  EXPECT_NEAR(s.slip_mm[0], 2.7 * kThr, 1e-9);
}

// The friction estimate is the largest load ratio held for two frames; a fall of the shear force
// from the cone's edge is a breakaway, even when the element's centroid barely moved.
TEST(FieldDetector, FrictionIsLearnedAndABreakawayIsASlip) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.8);
  det.update(0, tip.in, kThr, {});
  EXPECT_DOUBLE_EQ(det.update(0, tip.in, kThr, {}).mu_estimate, 0.8);
  tip.r[3].fx = 0.3 * 0.5;  // 0.8 -> 0.3 of F_n: the spring let go
  tip.r[3].dx_mm = -0.5 * kThr;
  tip.sync();
  const FingertipSlip& s = det.update(0, tip.in, kThr, {});
  EXPECT_TRUE(slipping(s.state[3]));
  EXPECT_EQ(s.slipping, 1U);
  EXPECT_DOUBLE_EQ(s.mu_estimate, 0.8);
}

// A slipping element stays slipping at the cone's edge while the arm drives the contact, and
// stops when the arm stops.
TEST(FieldDetector, SlipContinuesAtTheConesEdgeWhileTheArmMoves) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.8);
  det.update(0, tip.in, kThr, {});
  det.update(0, tip.in, kThr, {});
  tip.move_all(3 * kThr, 0.0);
  EXPECT_EQ(det.update(0, tip.in, kThr, {}).slipping, tip.r.size());
  tip.move_all(0.1 * kThr, 0.0);
  const ArmMotion turning{0.0, 0.5};
  EXPECT_EQ(det.update(0, tip.in, kThr, turning).slipping, tip.r.size());
  EXPECT_EQ(det.update(0, tip.in, kThr, {}).slipping, 0U);
}

// A frame seen again decides nothing and keeps the history.
TEST(FieldDetector, AFrameSeenAgainDecidesNothing) {
  SlipDetector det(field_config());
  Tip tip(0.5, 0.3);
  det.update(0, tip.in, kThr, {});
  tip.move_all(0.0, 3 * kThr);
  tip.in.fresh = false;
  EXPECT_EQ(det.update(0, tip.in, kThr, {}).slipping, 0U);
  tip.in.fresh = true;
  EXPECT_EQ(det.update(0, tip.in, kThr, {}).slipping, tip.r.size());
}

// Whatever the readings hold, the decisions and numbers stay finite and the states valid.
// Random readings with NaN, infinities and extremes: every output stays finite, and with `learned`
// every signal too.
void expect_finite_on_every_input(SlipDetectorKind kind) {
  Config cfg;
  cfg.slip_detector = kind;
  SlipDetector det(cfg);
  std::mt19937_64 rng(11);
  const double specials[] = {std::numeric_limits<double>::quiet_NaN(),
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             1e308,
                             -1e308,
                             0.0,
                             1e-300,
                             std::numeric_limits<double>::denorm_min()};
  std::uniform_int_distribution<int> pick(0, 15);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto value = [&] {
    const int p = pick(rng);
    return p < 8 ? specials[p] : u(rng);
  };
  for (int frame = 0; frame < 3000; ++frame) {
    Tip tip;
    for (ElementReading& e : tip.r) {
      e.contact = pick(rng) % 2 == 0;
      e.has_displacement = pick(rng) % 3 != 0;
      e.dx_mm = value();
      e.dy_mm = value();
      e.fx = value();
      e.fy = value();
      e.fz = value();
      e.x_px = pick(rng) == 0 ? value() : e.x_px;
    }
    tip.sync();
    tip.in.camera_timestamp_ns =
        std::int64_t{frame} * 5'000'000 + (pick(rng) == 0 ? -7'000'000 : 0);
    const ArmMotion arm{value(), value()};
    const std::size_t f = static_cast<std::size_t>(frame % 2);
    const FingertipSlip& s = det.update(f, tip.in, kThr, arm);
    ASSERT_TRUE(std::isfinite(s.rigid_mm)) << frame;
    ASSERT_TRUE(std::isfinite(s.mu_estimate)) << frame;
    for (std::size_t i = 0; i < kMaxSlipElements; ++i) {
      ASSERT_TRUE(std::isfinite(s.slip_mm[i])) << frame;
      ASSERT_LE(static_cast<int>(s.state[i]), static_cast<int>(ElementSlipState::kSlip));
      if (!det.has_features(f)[i]) continue;
      for (float v : det.features(f, i))
        ASSERT_TRUE(std::isfinite(v)) << frame;
    }
  }
}

TEST(FieldDetector, FiniteOnEveryInput) {
  expect_finite_on_every_input(SlipDetectorKind::kField);
}

TEST(ArmMotionEstimator, SpeedAndYawRateFromSuccessivePoses) {
  ArmMotionEstimator est;
  EXPECT_EQ(est.update({{0, 0, 0}, 0.0}, 1.0).speed_mps, 0.0);
  const ArmMotion m = est.update({{0.003, 0.004, 0}, -0.05}, 1.1);
  EXPECT_NEAR(m.speed_mps, 0.05, 1e-12);
  EXPECT_NEAR(m.yaw_rate_rps, -0.5, 1e-12);
  // A time that does not advance keeps the last motion; a non-finite pose gives none.
  EXPECT_NEAR(est.update({{1, 1, 1}, 3.0}, 1.1).speed_mps, 0.05, 1e-12);
  EXPECT_EQ(est.update({{std::nan(""), 0, 0}, 0.0}, 1.2).speed_mps, 0.0);
}

// The learned combiner (docs/slip.md, "The learned combiner"): a trained model is compiled in,
// and every element with signals is decided by it, score against the decision level.
Config learned_config() {
  Config c;
  c.slip_detector = SlipDetectorKind::kLearned;
  return c;
}

TEST(LearnedDetector, ATrainedModelIsCompiledIn) {
  EXPECT_STREQ(to_string(SlipSignal::kFieldReasons), "field_reasons");
  EXPECT_STREQ(kSlipFeatureNames[column(SlipSignal::kShareSlippingPrev)], "share_slipping_prev");
  EXPECT_GT(SlipDetector::model().trees(), 0U) << "slip_model.inc holds no trees: run slip_train";
  EXPECT_GT(SlipDetector::model(GripKind::kMargin).trees(), 0U)
      << "slip_model_margin.inc holds no trees: run slip_train --grip mixed";
  EXPECT_EQ(&SlipDetector::model(), &SlipDetector::model(GripKind::kPaper));
  EXPECT_NE(&SlipDetector::model(GripKind::kMargin), &SlipDetector::model(GripKind::kPaper));
  EXPECT_EQ(slip_detector_from_string("learned"), SlipDetectorKind::kLearned);
  EXPECT_STREQ(to_string(SlipDetectorKind::kLearned), "learned");
}

// Each grip's detector by its own model (docs/slip.md, "One model per grip").
class LearnedDetectorOfGrip : public ::testing::TestWithParam<GripKind> {};

TEST_P(LearnedDetectorOfGrip, DecidesEachElementByTheModelsScore) {
  Config cfg = learned_config();
  cfg.grip = GetParam();
  SlipDetector det(cfg);
  SlipDetector field(field_config());  // fed the same frames: its rules are among the signals
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::size_t decided = 0, slipped = 0;
  for (int frame = 0; frame < 400; ++frame) {
    // A loaded contact dragged along y, faster and slower, its grip rising and falling.
    Tip tip(0.5 + 0.3 * std::sin(frame * 0.05), 0.2 + 0.2 * std::abs(std::sin(frame * 0.02)));
    for (ElementReading& e : tip.r) {
      e.dx_mm = kThr * u(rng);
      e.dy_mm = kThr * (1.5 * std::sin(frame * 0.1) + u(rng));
    }
    tip.sync();
    const FingertipSlip& s = det.update(0, tip.in, kThr, ArmMotion{0.01, 0.0});
    const FingertipSlip& rules = field.update(0, tip.in, kThr, ArmMotion{0.01, 0.0});
    for (std::size_t i = 0; i < tip.r.size(); ++i) {
      ASSERT_TRUE(det.has_features(0)[i]);
      const SlipFeatures x = det.features(0, i);
      // The field rules' reasons, not the model's: slip_train's rows do not depend on the model.
      ASSERT_EQ(x[column(SlipSignal::kFieldReasons)], static_cast<float>(rules.reasons[i]))
          << "frame " << frame << " element " << i;
      for (float v : x)
        ASSERT_TRUE(std::isfinite(v));
      const bool model = SlipDetector::model(cfg.grip).score(x) >
                         static_cast<float>(SlipDetector::model_decision(cfg.grip));
      ASSERT_EQ(slipping(s.state[i]), model) << "frame " << frame << " element " << i;
      ASSERT_EQ(s.reasons[i] != 0, model);
      ++decided;
      slipped += model ? 1 : 0;
    }
  }
  // The stream holds both answers.
  EXPECT_GT(slipped, 0U);
  EXPECT_LT(slipped, decided);
}

INSTANTIATE_TEST_SUITE_P(Grips, LearnedDetectorOfGrip,
                         ::testing::Values(GripKind::kPaper, GripKind::kMargin),
                         [](const auto& p) { return std::string(to_string(p.param)); });

// An element without contact or without a displacement has no signals and does not slip.
TEST(LearnedDetector, NoSignalsWithoutADisplacement) {
  SlipDetector det(learned_config());
  Tip tip(0.5, 0.3);
  tip.r[0].contact = false;
  tip.r[1].has_displacement = false;
  tip.move_all(0.0, 5 * kThr);
  tip.sync();
  const FingertipSlip& s = det.update(0, tip.in, kThr, {});
  EXPECT_FALSE(det.has_features(0)[0]);
  EXPECT_FALSE(det.has_features(0)[1]);
  EXPECT_TRUE(det.has_features(0)[2]);
  EXPECT_FALSE(slipping(s.state[0]));
  EXPECT_FALSE(slipping(s.state[1]));
}

TEST(LearnedDetector, FiniteOnEveryInput) {
  expect_finite_on_every_input(SlipDetectorKind::kLearned);
}

// The frame's elements scored at once, by the vector path (AVX2 where the processor has it) and
// by the portable loop, give the model's own scores to the bit, whatever the count of elements:
// values on the model's usual thresholds (0, 1, ninths, small integers), beyond every threshold
// and NaN among them.
TEST(LearnedDetector, EveryScoringPathGivesTheModelsScoresExactly) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  for (const GripKind grip : {GripKind::kPaper, GripKind::kMargin}) {
    EXPECT_STREQ(SlipDetector::model(grip).vector_scoring(),
                 __builtin_cpu_supports("avx2") ? "avx2" : "portable");
  }
#endif
  std::mt19937_64 rng(11);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::uniform_int_distribution<int> kind(0, 9), small(0, 30);
  const auto value = [&]() -> float {
    switch (kind(rng)) {
      case 0:
        return 0.0f;
      case 1:
        return static_cast<float>(small(rng)) / 9.0f;
      case 2:
        return static_cast<float>(small(rng));
      case 3:
        return kind(rng) < 5 ? std::numeric_limits<float>::infinity()
                             : -std::numeric_limits<float>::infinity();
      case 4:
        return std::numeric_limits<float>::quiet_NaN();
      default:
        return normal(rng) * (kind(rng) < 5 ? 0.01f : 2.0f);
    }
  };
  std::size_t compared = 0;
  for (const GripKind grip : {GripKind::kPaper, GripKind::kMargin}) {
    const ObliviousForest& forest = SlipDetector::model(grip);
    for (int draw = 0; draw < 40; ++draw) {
      SlipColumns columns{};
      for (auto& column : columns)
        for (float& v : column)
          v = value();
      for (std::size_t n : {0, 1, 7, 8, 9, 31, 32, 33, 41, 63, 64}) {
        testing::expect_every_path_scores_exactly(
            forest, columns, n, std::string(to_string(grip)) + ", draw " + std::to_string(draw),
            compared);
        if (::testing::Test::HasFatalFailure()) return;
      }
    }
  }
  EXPECT_EQ(compared, 2 * 40U * (1 + 7 + 8 + 9 + 31 + 32 + 33 + 41 + 63 + 64));
}

}  // namespace
}  // namespace tactile::control
