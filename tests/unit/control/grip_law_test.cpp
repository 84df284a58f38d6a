// The margin grip (docs/control.md, "The margin grip"): the servo's direction and bounds, the F2
// bound, the force-rate limit, the friction estimate on slip and without, the relax after a safe
// while, the feed-forward ahead of a planned acceleration, Phase II's target and non-finite
// inputs. Table-driven where the law gives rules.
#include "tactile/control/grip_law.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace tactile::control {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kDt = 0.01;

Config margin_config() {
  Config c;
  c.grip = GripKind::kMargin;
  return c;
}

// mu_hat stays where the loads put it: the feed-forward's and the twist's figures are exact.
Config steady_mu_config() {
  Config c = margin_config();
  c.grip_mu_rise_per_s = 0;
  return c;
}

// Both fingertips press alike: one element each with normal force `fz` and tangential load
// `load` along y_f (gravity); `slip` raises SLIP on both.
class Grip {
 public:
  explicit Grip(const Config& cfg = margin_config(), double dt = kDt)
      : cfg_(cfg), law_(cfg), dt_(dt) {
    for (auto& tip : elements_)
      tip.resize(1);
  }
  void press(double fz, double load) {
    for (auto& tip : elements_) {
      tip[0].contact = fz > 0;
      tip[0].fz = fz;
      tip[0].fy = load;
    }
  }
  GripOutput step(bool slip = false, GripContext ctx = {}) {
    std::array<FingertipInput, kFingertips> in{};
    Flags flags;
    for (std::size_t f = 0; f < kFingertips; ++f) {
      in[f].elements = elements_[f];
      in[f].fresh = true;
      FingertipFlags& ff = flags.fingertip[f];
      ff.total_fz_n = elements_[f][0].contact ? elements_[f][0].fz : 0.0;
      ff.contact_elements = elements_[f][0].contact ? 1U : 0U;
      ff.max_fz_n = ff.total_fz_n;
      ff.max_fz_index = 0;
      ff.slip = slip;
    }
    flags.slip = slip;
    const GripOutput out = law_.update(flags, in, ctx, t_);
    t_ += dt_;
    return out;
  }
  // `seconds` of updates without slip.
  void hold(double seconds, GripContext ctx = {}) {
    for (double s = 0; s < seconds; s += dt_)
      step(false, ctx);
  }
  GripLaw& law() { return law_; }
  const Config& cfg() const { return cfg_; }
  double t() const { return t_; }

 private:
  Config cfg_;
  GripLaw law_;
  std::array<std::vector<ElementReading>, kFingertips> elements_;
  double dt_;
  double t_ = 0;
};

TEST(GripLaw, ServoSqueezesTowardTheTargetAndNoFaster) {
  struct Case {
    double grip_n;
    double sign;  // of the squeeze
    const char* what;
  };
  // No load: the target is grip_min_n (0.1 N).
  const Case cases[] = {{0.06, 1.0, "under the target: squeeze"},
                        {0.3, -1.0, "over the target: open"},
                        {0.02, 1.0, "far under: squeeze at the bound"},
                        {2.0, -1.0, "far over: open at the bound"}};
  for (const Case& c : cases) {
    Grip g;
    g.press(c.grip_n, 0.0);
    // The reference starts at the grip and follows the target at the force rate.
    GripOutput out = g.step();
    for (int i = 0; i < 100; ++i)
      out = g.step();
    EXPECT_EQ(std::copysign(1.0, out.squeeze_mps), c.sign) << c.what;
    EXPECT_LE(std::abs(out.squeeze_mps), g.cfg().grip_servo_max_speed_mps + 1e-15) << c.what;
    const double expected =
        std::clamp(g.cfg().grip_servo_gain_mps_per_n * (g.law().target_n() - c.grip_n),
                   -g.cfg().grip_servo_max_speed_mps, g.cfg().grip_servo_max_speed_mps);
    EXPECT_NEAR(out.squeeze_mps, expected, 1e-12) << c.what;
  }
}

// The speed holds for a whole update: at a longer period (a slower camera) the gain falls in
// proportion past grip_servo_gain_period_s, so each period closes the same part of the error.
TEST(GripLaw, TheServosGainFallsWithALongerPeriod) {
  struct Case {
    double dt;
    double gain_fraction;
  };
  const Config cfg = margin_config();
  const double p = cfg.grip_servo_gain_period_s;
  const Case cases[] = {{0.002, 1.0}, {p, 1.0}, {2 * p, 0.5}, {4 * p, 0.25}};
  for (const Case& c : cases) {
    Grip g(cfg, c.dt);
    g.press(0.08, 0.0);  // under the target grip_min_n (0.1 N): a small error, under the bound
    GripOutput out = g.step();
    for (int i = 0; i < 50; ++i)
      out = g.step();
    const double error = g.law().reference_n() - 0.08;
    ASSERT_GT(error, 0.0) << c.dt;
    EXPECT_LT(cfg.grip_servo_gain_mps_per_n * error, cfg.grip_servo_max_speed_mps) << c.dt;
    EXPECT_NEAR(out.squeeze_mps, c.gain_fraction * cfg.grip_servo_gain_mps_per_n * error, 1e-12)
        << c.dt;
  }
}

// What the arm waits for before it moves a grasped object (GraspSearch's settle).
TEST(GripLaw, ReachedOnlyWithinTheServosReachOfTheTarget) {
  Grip g;
  EXPECT_FALSE(g.law().reached()) << "before the first update";
  g.press(0.02, 0.0);  // a fifth of the target grip_min_n
  g.step();
  EXPECT_FALSE(g.law().reached());
  g.press(0.095, 0.0);  // 95 % of it
  g.step();
  EXPECT_TRUE(g.law().reached());
}

TEST(GripLaw, NoSqueezePastTheF2Bound) {
  Grip g;
  const double limit = g.cfg().recompress_max_f2_fraction * g.cfg().f2_n;
  // A load that asks for far more than the bound allows.
  g.press(limit, 3.0);
  GripOutput out;
  for (int i = 0; i < 20; ++i)
    out = g.step();
  EXPECT_GT(g.law().target_n(), limit);
  EXPECT_LE(out.squeeze_mps, 0.0);
  g.press(0.99 * limit, 3.0);
  EXPECT_GT(g.step().squeeze_mps, 0.0) << "under the bound the servo squeezes again";
}

TEST(GripLaw, TheReferenceFollowsTheTargetAtTheForceRate) {
  Grip g;
  g.press(0.2, 0.08);  // the demand: 0.08 / 0.5 x 1.25 = 0.2 N
  g.step();
  EXPECT_NEAR(g.law().reference_n(), 0.2, 1e-12) << "the reference starts at the grip";
  // A slip asks for 0.26 N at once; the reference takes it in steps of rate x dt.
  g.step(true);
  const double step = g.cfg().grip_force_rate_nps * kDt;
  EXPECT_NEAR(g.law().target_n(), 0.2 * (1 + g.cfg().grip_slip_step), 1e-12);
  // A load that needs 3 N: the target jumps, the reference does not.
  g.press(0.2, 1.0);
  double before = g.law().reference_n();
  for (int i = 0; i < 5; ++i) {
    g.step();
    EXPECT_NEAR(g.law().reference_n() - before, step, 1e-9) << i;
    before = g.law().reference_n();
  }
}

TEST(GripLaw, SlipLowersTheFrictionEstimateToItsLoadRatio) {
  struct Case {
    double fz;
    double load;
    double mu_after;
    const char* what;
  };
  const double mu0 = margin_config().grip_mu_initial;  // 0.5
  const double floor = (1 - margin_config().grip_mu_drop) * mu0;
  const Case cases[] = {
      {0.5, 0.2, 0.4, "slip at a ratio below mu_hat: mu_hat is the ratio"},
      {0.5, 0.15, floor, "a ratio far below: by at most grip_mu_drop"},
      {0.5, 0.03, mu0, "a demand at grip_min_n: the estimate did not set the grip"},
      {0.04, 0.01, mu0, "a touch lighter than grip_min_n gives no ratio"},
  };
  for (const Case& c : cases) {
    Grip g;
    g.press(c.fz, 0.0);
    g.step();
    g.press(c.fz, c.load);
    g.step(true);
    EXPECT_NEAR(g.law().mu_hat(), c.mu_after, 1e-12) << c.what;
  }
  // A slip while a planned acceleration is near is the load arriving, not news of the friction.
  {
    Grip g;
    GripContext ahead;
    ahead.accelerates_soon = true;
    g.press(0.5, 0.2);
    g.step(true, ahead);
    EXPECT_NEAR(g.law().mu_hat(), mu0, 1e-12);
  }
  // A slip at a ratio above mu_hat does not raise it; carrying that ratio without slip does.
  Grip g;
  g.press(0.5, 0.4);
  g.step(true);
  EXPECT_NEAR(g.law().mu_hat(), mu0, 1e-12);
  g.step(false);
  EXPECT_NEAR(g.law().mu_hat(), 0.8, 1e-12) << "a ratio carried without slip bounds mu below";
}

TEST(GripLaw, FrictionEstimateRisesSlowlyAfterASafeWhileUpToTheSlipsCeiling) {
  Config cfg = margin_config();
  cfg.grip_mu_rise_per_s = 0.1;
  Grip g{cfg};
  g.press(0.5, 0.2);
  g.step(true);  // mu_hat 0.5 -> 0.4; the ceiling: the middle of the drop, 0.425
  EXPECT_NEAR(g.law().mu_hat(), 0.4, 1e-12);
  g.hold(0.9 * cfg.grip_safe_s);
  EXPECT_NEAR(g.law().mu_hat(), 0.4, 1e-12) << "not within the safe while";
  g.hold(0.3);
  EXPECT_GT(g.law().mu_hat(), 0.4);
  EXPECT_LT(g.law().mu_hat(), 0.425);
  g.hold(10.0);
  EXPECT_NEAR(g.law().mu_hat(), (1 - 0.5 * cfg.grip_mu_drop) * 0.5, 1e-12) << "the ceiling";
  // The default does not probe at all.
  Grip still;
  still.press(0.5, 0.2);
  still.hold(5.0);
  EXPECT_NEAR(still.law().mu_hat(), margin_config().grip_mu_initial, 1e-12);
}

TEST(GripLaw, TargetRaisedAtOnceOnSlipAndRelaxedAfterASafeWhile) {
  Grip g;
  g.press(0.3, 0.1);  // demand 0.1 / 0.5 x 1.25 = 0.25 N
  g.step();
  EXPECT_NEAR(g.law().demand_n(), 0.25, 1e-12);
  g.step(true);  // the ratio 0.33 lowers mu_hat by grip_mu_drop, to 0.35
  const double raised = g.law().target_n();
  EXPECT_NEAR(raised, std::max(g.law().demand_n(), 0.3) * (1 + g.cfg().grip_slip_step), 1e-12);
  g.hold(0.9 * g.cfg().grip_safe_s);
  EXPECT_NEAR(g.law().target_n(), raised, 1e-12) << "held through the safe while";
  g.hold(0.2);
  EXPECT_LT(g.law().target_n(), raised) << "relaxing after it";
  g.hold(10.0);
  EXPECT_NEAR(g.law().target_n(), g.law().demand_n(), 1e-3) << "down to the demand";
}

TEST(GripLaw, AFirmGripThatSlipsStopsRelaxingWhereItIs) {
  Grip g;
  g.press(0.3, 0.1);  // demand 0.25 N; the slip raises the target to 0.39 N
  g.step();
  g.step(true);
  g.press(0.39, 0.1);
  g.hold(1.5);  // relaxing toward the demand
  const double relaxing = g.law().target_n();
  ASSERT_LT(relaxing, 0.39);
  g.press(1.3 * relaxing, 0.1);  // a grip past a raise of the demand, and past the target
  GripContext shaken;            // the arm's start: the friction estimate stays, so does the demand
  shaken.accelerates_soon = true;
  g.step(true, shaken);
  EXPECT_NEAR(g.law().target_n(), std::max(relaxing, g.law().demand_n()), 1e-12)
      << "the target holds: not raised to the grip measured";
  const double held = g.law().target_n();
  g.hold(0.9 * g.cfg().grip_safe_s);
  EXPECT_NEAR(g.law().target_n(), held, 1e-12) << "held through the safe while";
}

// The grip measured swings with the arm's vibration; slips (false ones too) at its peaks do not
// ratchet the target up by the swing: before, each took the target to the grip's peak.
TEST(GripLaw, SlipsAtTheVibrationsPeaksDoNotRatchetTheTarget) {
  Grip g;
  g.press(0.6, 0.1);
  g.step();
  for (int i = 0; i < 20; ++i) {
    const bool peak = i % 2 == 0;
    g.press(peak ? 0.66 : 0.54, 0.1);  // +-10 % around 0.6 N
    g.step(peak);
  }
  EXPECT_NEAR(g.law().target_n(), g.law().demand_n(), 1e-12);
  EXPECT_LT(g.law().target_n(), 0.54) << "under every grip measured";
}

// A slide, three slip frames in a row, is no vibration's peak: a firm grip goes up from what it
// is, and the reference with it at once (the seed-20 sweep's scenario 189: a pull of 0.63 N on
// an 80 g cap; the firm grip kept its target, the servo eased off the sliding cap and it left in
// 60 ms). One or two in a row keep the target (the peaks of a vibration).
TEST(GripLaw, ASlideRaisesEvenAFirmGripAtOnce) {
  struct Case {
    int slips;
    double target_n;
  };
  const double demand = 0.1 / 0.5 * 1.25;  // 0.25 N
  const Case cases[] = {{1, demand}, {2, demand}, {3, 0.6 * 1.3}, {4, 0.6 * 1.3 * 1.3}};
  Config cfg = margin_config();
  cfg.grip_mu_min = cfg.grip_mu_max = cfg.grip_mu_initial;  // the slips leave the demand alone
  for (const Case& c : cases) {
    Grip g{cfg};
    g.press(0.6, 0.1);  // firm: over the demand's raise
    g.step();
    for (int i = 0; i < c.slips; ++i) {
      g.step(true);
      g.press(std::max(0.6, g.law().target_n()), 0.1);  // a raise takes effect
    }
    EXPECT_NEAR(g.law().target_n(), c.target_n, 1e-12) << c.slips << " slip frames in a row";
    if (c.slips >= 3) {
      EXPECT_EQ(g.law().reference_n(), g.law().target_n()) << c.slips;
    }
  }
  // In the lift's loading phase the contact slips as the weight arrives, and on a cap anchored to
  // the table in every frame: no slide there (it compounded the seed-20 sweep's scenario 7 to
  // 35 N per fingertip within 0.3 s).
  Grip loading{cfg};
  GripContext ctx;
  ctx.loading = true;
  loading.press(0.6, 0.1);
  loading.step(false, ctx);
  for (int i = 0; i < 6; ++i)
    loading.step(true, ctx);
  EXPECT_NEAR(loading.law().target_n(), demand, 1e-12) << "slips of the loading phase";
}

// Without the lift's loading phase (grip_loading_speed_mps 0), the lift's floor grip_lift_n
// holds until the lift has weighed the object: carried grip_load_window_s past its planned
// acceleration; then the demand is the load's. A new grasp has its floor again. With the loading
// phase (the default) there is no floor: the grip follows the weight as it arrives.
TEST(GripLaw, TheLiftsFloorLastsUntilTheLiftHasWeighedTheObject) {
  Config cfg = steady_mu_config();
  cfg.grip_loading_speed_mps = 0;
  Grip g{cfg};
  GripContext grasp;
  grasp.lifting = true;
  GripContext lift = grasp;
  lift.carrying = true;
  GripContext lift_start = lift;
  lift_start.accelerates_soon = true;
  const double carried = 0.05 / 0.5 * 1.25;  // each fingertip carries 0.05 N
  g.press(1.0, 0.05);
  g.hold(1.0, grasp);
  EXPECT_EQ(g.law().demand_n(), g.cfg().grip_lift_n) << "grasping";
  g.hold(1.0, lift_start);
  EXPECT_GE(g.law().demand_n(), g.cfg().grip_lift_n) << "the lift's acceleration does not weigh";
  g.hold(0.5 * g.cfg().grip_load_window_s, lift);
  EXPECT_EQ(g.law().demand_n(), g.cfg().grip_lift_n) << "half the window carried";
  g.hold(0.6 * g.cfg().grip_load_window_s, lift);
  EXPECT_NEAR(g.law().demand_n(), carried, 1e-9) << "weighed";
  g.law().reset();
  g.step(false, grasp);
  EXPECT_EQ(g.law().demand_n(), g.cfg().grip_lift_n) << "a new grasp";

  Grip loads_first{steady_mu_config()};
  ASSERT_TRUE(lift_loads_first(loads_first.cfg()));
  loads_first.press(1.0, 0.05);
  loads_first.hold(1.0, grasp);
  EXPECT_NEAR(loads_first.law().demand_n(), carried, 1e-9) << "the load's, in the grasp already";
  loads_first.press(1.0, 0.0);
  loads_first.hold(1.0, grasp);
  EXPECT_EQ(loads_first.law().demand_n(), loads_first.cfg().grip_min_n) << "no load, the least";
  GripContext loading = lift;
  loading.loading = true;
  loads_first.press(1.0, 0.4);  // an anchored cap's pull: the load asks 1 N
  loads_first.hold(0.1, loading);
  EXPECT_EQ(loads_first.law().demand_n(), loads_first.cfg().grip_lift_n) << "loading: at most";
  loads_first.hold(0.1, lift);
  EXPECT_NEAR(loads_first.law().demand_n(), 1.0, 1e-9) << "the lift proper: the load's";
}

// A slip short of the target: the servo squeezes at its full speed for recompress_duration_s
// after the slip, then by its gain again.
TEST(GripLaw, ASlipShortOfTheTargetSqueezesAtFullSpeed) {
  Grip g;
  g.press(0.5, 0.16);  // demand 0.4 N; the slip raises the target to 0.65 N
  g.step();
  const GripOutput slip = g.step(true);
  ASSERT_NEAR(g.law().target_n(), 0.65, 1e-12);
  const double full = g.cfg().grip_servo_max_speed_mps;
  const double by_gain = g.cfg().grip_servo_gain_mps_per_n * (0.65 - 0.5);
  ASSERT_LT(by_gain, full);
  EXPECT_EQ(slip.squeeze_mps, full);
  const double slip_t = g.t() - kDt;
  GripOutput out = g.step();
  EXPECT_EQ(out.squeeze_mps, full) << "within recompress_duration_s";
  while (g.t() <= slip_t + g.cfg().recompress_duration_s + 1e-9)
    out = g.step();
  out = g.step();
  EXPECT_NEAR(out.squeeze_mps, g.cfg().grip_servo_gain_mps_per_n * (g.law().target_n() - 0.5),
              1e-12)
      << "by the gain after it";
  EXPECT_LT(out.squeeze_mps, full);
}

// The servo on a plant with the rig's contact: a dome of 41 feelers, each a 1.5 N/mm spring,
// touching one after another as the fingertip presses (every 0.02 mm), so a firm grip is ten
// times as stiff as a light one; and the finger's move is seen one frame late (the command acts
// over the next period, docs/rig.md). With one gain for any stiffness the loop rang at the firm
// grip (the seed-20 sweep's scenario 118 at 143 fps: 1.0-1.7 N, a cycle of four frames). Per
// element in contact it settles at the light grip and the firm one alike, at every camera rate.
TEST(GripLaw, TheServoSettlesOnAFirmGripAsOnALightOne) {
  constexpr int kElements = 41;
  constexpr double kStiffnessNPerM = 1500.0;
  constexpr double kOnsetM = 2e-5;
  struct Case {
    double fps;
    double target_n;  // what the load asks, mu_hat 0.5 and the margin 0.25
  };
  const Case cases[] = {{30, 0.2},  {30, 1.4},  {71, 0.2},  {71, 1.4}, {143, 0.2},
                        {143, 1.4}, {143, 2.0}, {500, 0.2}, {500, 1.4}};
  for (const Case& c : cases) {
    Config cfg = steady_mu_config();
    cfg.grip_mu_min = cfg.grip_mu_max = cfg.grip_mu_initial;  // the demand is the target
    GripLaw law(cfg);
    const double dt = 1.0 / c.fps;
    const double load = c.target_n * cfg.grip_mu_initial / (1.0 + cfg.grip_margin);
    double depth_m = 0;        // each fingertip's, toward the cap
    double pending_mps = 0;    // the command of the last update: it acts over the next period
    std::vector<double> late;  // the grip over the last second
    std::array<FingertipInput, kFingertips> in{};
    std::array<std::vector<ElementReading>, kFingertips> elements;
    for (auto& tip : elements)
      tip.resize(kElements);
    const int frames = static_cast<int>(3.0 * c.fps);
    for (int k = 0; k < frames; ++k) {
      Flags flags;
      double grip = 0;
      for (std::size_t f = 0; f < kFingertips; ++f) {
        double total = 0;
        std::uint32_t touching = 0;
        for (int e = 0; e < kElements; ++e) {
          ElementReading& r = elements[f][static_cast<std::size_t>(e)];
          r.fz = kStiffnessNPerM * std::max(0.0, depth_m - e * kOnsetM);
          r.contact = r.fz > 0;
          r.fy = 0;
          total += r.fz;
          touching += r.contact ? 1U : 0U;
        }
        elements[f][0].fy = load;  // the load, carried (its place does not matter to the law)
        in[f].elements = elements[f];
        in[f].fresh = true;
        flags.fingertip[f].total_fz_n = total;
        flags.fingertip[f].contact_elements = touching;
        flags.fingertip[f].max_fz_n = elements[f][0].fz;
        flags.fingertip[f].max_fz_index = 0;
        grip = total;
      }
      const GripOutput out = law.update(flags, in, GripContext{}, k * dt);
      depth_m = std::max(0.0, depth_m + pending_mps * dt);
      pending_mps = out.squeeze_mps;
      if (k * dt >= 2.0) late.push_back(grip);
    }
    ASSERT_FALSE(late.empty());
    const auto [lo, hi] = std::minmax_element(late.begin(), late.end());
    EXPECT_LT(*hi - *lo, 0.02 * c.target_n) << c.fps << " fps, " << c.target_n << " N";
    EXPECT_NEAR(late.back(), c.target_n, 0.05 * c.target_n) << c.fps << " fps";
  }
}

// After a pause (a stale hold), the time without data is no control step and no safe while: the
// target does not relax in the first update after it, and only grip_safe_s of updates later.
TEST(GripLaw, APauseIsNeitherAStepNorASafeWhile) {
  Grip g;
  g.press(0.3, 0.1);
  g.step();
  g.step(true);  // the target raised above the demand
  const double raised = g.law().target_n();
  g.hold(0.9 * g.cfg().grip_safe_s);
  ASSERT_EQ(g.law().target_n(), raised);
  g.law().pause();
  g.hold(0.9 * g.cfg().grip_safe_s);
  EXPECT_EQ(g.law().target_n(), raised) << "the safe while starts again after the pause";
  g.hold(0.2 * g.cfg().grip_safe_s);
  EXPECT_LT(g.law().target_n(), raised) << "relaxing a safe while after it";
}

TEST(GripLaw, DemandIsTheLoadOverTheFrictionEstimateWithTheMargin) {
  struct Case {
    double load;
    double demand;
  };
  const Config c = margin_config();
  const Case cases[] = {
      {0.0, c.grip_min_n}, {0.02, c.grip_min_n}, {0.1, 0.1 / 0.5 * 1.25}, {0.4, 0.4 / 0.5 * 1.25}};
  for (const Case& k : cases) {
    Grip g;
    g.press(10.0, k.load);  // a grip far above the ratio: mu_hat stays at its start
    g.step();
    EXPECT_NEAR(g.law().demand_n(), k.demand, 1e-12) << k.load;
  }
}

TEST(GripLaw, FeedForwardAheadOfAPlannedAcceleration) {
  Grip g{steady_mu_config()};
  GripContext carry;
  carry.carrying = true;
  g.press(1.0, 0.1);  // each fingertip carries 0.1 N: the weight is 0.2 N
  g.hold(3.0, carry);
  EXPECT_NEAR(g.law().weight_n(), 0.2, 1e-6);
  const double steady = g.law().demand_n();
  GripContext ahead = carry;
  ahead.accelerates_soon = true;
  g.step(false, ahead);
  const double ff = 0.5 * g.law().weight_n() * g.cfg().grip_ff_accel_mps2 / 9.81;
  EXPECT_NEAR(g.law().demand_n() - steady, ff / g.law().mu_hat() * (1 + g.cfg().grip_margin), 1e-9);
  EXPECT_GE(g.law().target_n(), g.law().demand_n()) << "raised before the acceleration";
}

TEST(GripLaw, PhaseTwoHasItsOwnTarget) {
  Grip g{steady_mu_config()};
  GripContext carry;
  carry.carrying = true;
  g.press(1.0, 0.1);
  g.hold(3.0, carry);  // the weight: 0.2 N
  const double mu = g.law().mu_hat();
  GripContext twist_grasp;
  twist_grasp.twist = true;
  twist_grasp.accelerates_soon = true;
  g.press(1.0, 0.0);  // seated on the thread: no load before the turn
  g.step(false, twist_grasp);
  EXPECT_NEAR(g.law().demand_n(), 0.1 / mu * (1 + g.cfg().grip_twist_margin), 1e-9)
      << "before the first turn: the carry's share of the weight, with the twist's margin";
  GripContext turn;
  turn.twist = true;
  g.press(1.0, 0.3);
  g.hold(0.5, turn);
  g.press(1.0, 0.0);
  g.step(false, twist_grasp);
  EXPECT_NEAR(g.law().demand_n(), 0.3 / g.law().mu_hat() * (1 + g.cfg().grip_twist_margin), 1e-9)
      << "before the next turn: the last turn's load";
}

TEST(GripLaw, NonFiniteInputsGiveFiniteOutputs) {
  struct Case {
    double fz;
    double load;
    const char* what;
  };
  const Case cases[] = {{kNan, 0.1, "NaN F_z"},
                        {0.3, kNan, "NaN F_t"},
                        {std::numeric_limits<double>::infinity(), 0.1, "infinite F_z"},
                        {0.3, std::numeric_limits<double>::infinity(), "infinite F_t"}};
  for (const Case& c : cases) {
    Grip g;
    g.press(0.3, 0.05);
    g.step();
    g.press(c.fz, c.load);
    for (int i = 0; i < 10; ++i) {
      const GripOutput out = g.step(i % 3 == 0);
      EXPECT_TRUE(std::isfinite(out.squeeze_mps)) << c.what;
    }
    EXPECT_TRUE(std::isfinite(g.law().target_n())) << c.what;
    EXPECT_TRUE(std::isfinite(g.law().mu_hat())) << c.what;
  }
  // A clock that is not finite: no step of time, still finite.
  GripLaw law{margin_config()};
  const std::array<FingertipInput, kFingertips> in{};
  const GripOutput out = law.update(Flags{}, in, GripContext{}, kNan);
  EXPECT_TRUE(std::isfinite(out.squeeze_mps));
}

TEST(GripLaw, ConfigRefusesBadParameters) {
  struct Case {
    double Config::*field;
    double value;
    const char* name;
  };
  const Case cases[] = {{&Config::grip_touch_n, 0.0, "grip_touch_n"},
                        {&Config::grip_touch_n, 0.6, "grip_touch_n"},
                        {&Config::grip_min_n, 0.04, "grip_min_n"},
                        {&Config::grip_margin, -0.1, "grip_margin"},
                        {&Config::grip_mu_initial, 2.0, "grip_mu_initial"},
                        {&Config::grip_mu_max, 0.1, "grip_mu_max"},
                        {&Config::grip_slip_step, 0.0, "grip_slip_step"},
                        {&Config::grip_relax_s, 0.0, "grip_relax_s"},
                        {&Config::grip_servo_max_speed_mps, 0.02, "grip_servo_max_speed_mps"},
                        {&Config::grip_force_rate_nps, kNan, "grip_force_rate_nps"}};
  for (const Case& c : cases) {
    Config cfg = margin_config();
    cfg.*(c.field) = c.value;
    try {
      cfg.validate();
      ADD_FAILURE() << c.name << " = " << c.value << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(c.name), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(grip_from_string("margin"), GripKind::kMargin);
  EXPECT_EQ(grip_from_string("paper"), GripKind::kPaper);
  EXPECT_FALSE(grip_from_string("Margin").has_value());
}

}  // namespace
}  // namespace tactile::control
