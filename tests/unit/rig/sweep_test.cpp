// The random scenario sweep (docs/slip.md, "The sweep"): the draw over many seeds (no rig runs),
// and tiny sweeps of real child rig processes, cut at a few seconds of simulated time.
#include "tactile/rig/sweep.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/scenario_run.hpp"
#include "tactile/rig/world.hpp"
#include "tactile/util/files.hpp"

namespace {

namespace fs = std::filesystem;
namespace sweep = tactile::rig::sweep;
using tactile::testing::ProcessResult;
using tactile::testing::TempDir;

constexpr const char* kRig = TACTILE_RIG_PATH;

// FNV-1a 64 of the seed-20 sweep's first 40 scenario files (without `sim`) as rig --sweep wrote
// them at 18f4c77, before the disturbances were drawn.
constexpr std::uint64_t kMainSeed20Hash = 0x4ea99effbf2d8e4ULL;

bool within(double v, sweep::Range r) {
  return v >= r.lo && v <= r.hi;
}

TEST(SweepDraw, EveryDrawLiesInItsDocumentedRangeAndItsFileStatesItExactly) {
  const sweep::Ranges& r = sweep::kRanges;
  // The ends the brief documents, checked against the constants, not through them.
  EXPECT_EQ(r.mass_kg.lo, 0.003);
  EXPECT_EQ(r.mass_kg.hi, 0.080);
  EXPECT_EQ(r.fps.lo, 60);
  EXPECT_EQ(r.fps.hi, 500);
  double lowest_mass = 1;
  double highest_mass = 0;
  int lowest_fps = 1000;
  int highest_fps = 0;
  std::set<int> depths;
  for (std::uint64_t seed : {0ULL, 1ULL, 2ULL, 77ULL, 0xFFFFFFFFFFFFFFFFULL}) {
    for (std::uint64_t i = 0; i < 2000; ++i) {
      const sweep::Draw d = sweep::draw_scenario(seed, i);
      ASSERT_EQ(d.index, i);
      EXPECT_TRUE(within(d.mass_kg, r.mass_kg)) << d.mass_kg;
      EXPECT_TRUE(within(d.radius_mm, r.radius_mm)) << d.radius_mm;
      EXPECT_TRUE(within(d.friction, r.friction)) << d.friction;
      EXPECT_TRUE(within(d.kinetic_ratio, r.kinetic_ratio)) << d.kinetic_ratio;
      EXPECT_TRUE(within(d.free_turn_deg, r.free_turn_deg)) << d.free_turn_deg;
      EXPECT_TRUE(within(d.vibration_mm, r.vibration_mm)) << d.vibration_mm;
      EXPECT_TRUE(within(d.vibration_hz, r.vibration_hz)) << d.vibration_hz;
      EXPECT_TRUE(within(d.noise_sigma, r.noise_sigma)) << d.noise_sigma;
      EXPECT_TRUE(within(d.fps, r.fps)) << d.fps;
      EXPECT_TRUE(d.bit_depth == 8 || d.bit_depth == 16) << d.bit_depth;
      lowest_mass = std::min(lowest_mass, d.mass_kg);
      highest_mass = std::max(highest_mass, d.mass_kg);
      lowest_fps = std::min(lowest_fps, d.fps);
      highest_fps = std::max(highest_fps, d.fps);
      depths.insert(d.bit_depth);
      if (i % 50 == 0) {
        // The scenario file reads back as the draw, bit for bit, through the strict parser.
        const tactile::rig::Scenario s =
            tactile::rig::parse_scenario(sweep::scenario_yaml(d), "drawn.yaml");
        EXPECT_EQ(s.seed, d.scenario_seed);
        EXPECT_EQ(s.world.cap.mass_kg, d.mass_kg);
        EXPECT_EQ(s.world.cap.radius_m, d.radius_mm / 1000.0);
        EXPECT_EQ(s.world.cap.friction, d.friction);
        EXPECT_EQ(s.world.cap.kinetic_ratio, d.kinetic_ratio);
        EXPECT_EQ(s.world.bottle.free_turn_deg, d.free_turn_deg);
        EXPECT_EQ(s.world.arm.vibration_m, d.vibration_mm / 1000.0);
        EXPECT_EQ(s.world.arm.vibration_hz, d.vibration_hz);
        EXPECT_EQ(s.camera.noise_sigma, d.noise_sigma);
        EXPECT_EQ(s.camera.fps, d.fps);
        EXPECT_EQ(s.camera.bit_depth, d.bit_depth);
        EXPECT_EQ(s.world.cap.held_to_table, d.scenario_case == sweep::Case::kCapHeld);
        if (d.scenario_case == sweep::Case::kBottleDisplaced) {
          EXPECT_EQ(s.world.bottle.displaced_x_m, d.displaced_x_mm / 1000.0);
          EXPECT_EQ(s.world.bottle.displaced_y_m, d.displaced_y_mm / 1000.0);
          // The lowering stops above the table, the only other support.
          ASSERT_EQ(s.controller.size(), 1U);
          EXPECT_EQ(s.controller[0].first, "lower_limit_m");
          EXPECT_EQ(s.controller[0].second, sweep::kDisplacedLowerLimitM);
        } else {
          EXPECT_EQ(s.world.bottle.displaced_x_m, 0.0);
          EXPECT_EQ(s.world.bottle.displaced_y_m, 0.0);
          EXPECT_TRUE(s.controller.empty()) << "the controller's defaults, no tuning";
        }
      }
      // Far enough that the cap, lowered over the controller's place, misses the neck.
      const double displaced = std::hypot(d.displaced_x_mm, d.displaced_y_mm);
      EXPECT_GE(displaced, sweep::kDisplacementMm.lo - 0.1);
      EXPECT_LE(displaced, sweep::kDisplacementMm.hi + 0.1);
      EXPECT_GT(displaced, 2 * sweep::kRanges.radius_mm.hi);
    }
  }
  // The whole range is drawn from, not a corner of it.
  EXPECT_LT(lowest_mass, 0.0035);
  EXPECT_GT(highest_mass, 0.0795);
  EXPECT_LE(lowest_fps, 61);
  EXPECT_GE(highest_fps, 499);
  EXPECT_EQ(depths, (std::set<int>{8, 16}));
}

// Exactly one displaced bottle and one held cap in every block of 10 indices, at places that
// change from block to block and seed to seed.
TEST(SweepDraw, EveryBlockOfTenHasOneOfEachNegativeCase) {
  std::set<std::uint64_t> displaced_at, held_at;
  for (std::uint64_t seed : {0ULL, 1ULL, 20ULL}) {
    for (std::uint64_t block = 0; block < 100; ++block) {
      int displaced = 0, held = 0;
      for (std::uint64_t i = block * 10; i < block * 10 + 10; ++i) {
        const sweep::Draw d = sweep::draw_scenario(seed, i);
        if (d.scenario_case == sweep::Case::kBottleDisplaced) {
          ++displaced;
          displaced_at.insert(i % 10);
        }
        if (d.scenario_case == sweep::Case::kCapHeld) {
          ++held;
          held_at.insert(i % 10);
        }
      }
      EXPECT_EQ(displaced, 1) << seed << " " << block;
      EXPECT_EQ(held, 1) << seed << " " << block;
    }
  }
  EXPECT_EQ(displaced_at.size(), 10U);
  EXPECT_EQ(held_at.size(), 10U);
  EXPECT_STREQ(sweep::to_string(sweep::Case::kNormal), "normal");
  EXPECT_STREQ(sweep::to_string(sweep::Case::kBottleDisplaced), "bottle_displaced");
  EXPECT_STREQ(sweep::to_string(sweep::Case::kCapHeld), "cap_held");
}

TEST(SweepDraw, AScenarioDependsOnlyOnTheSeedAndItsIndex) {
  const sweep::Draw late = sweep::draw_scenario(5, 123);
  for (std::uint64_t i = 0; i < 123; ++i)
    sweep::draw_scenario(5, i);
  EXPECT_EQ(sweep::scenario_yaml(sweep::draw_scenario(5, 123)), sweep::scenario_yaml(late));
  EXPECT_NE(sweep::scenario_yaml(sweep::draw_scenario(6, 123)), sweep::scenario_yaml(late));
  EXPECT_NE(sweep::scenario_yaml(sweep::draw_scenario(5, 124)), sweep::scenario_yaml(late));
}

// The disturbances' and fragility's shares (docs/slip.md, "Disturbances and fragile objects") over
// 1000 draws: a third disturbed, the four kinds alike, a fifth fragile; each value within its
// documented range and stated exactly by the file.
TEST(SweepDraw, DisturbancesAndFragileObjectsAreDrawnInTheirShares) {
  constexpr std::uint64_t kDraws = 1000;
  std::size_t disturbed = 0, fragile = 0;
  std::array<std::size_t, 5> kinds{};
  for (std::uint64_t i = 0; i < kDraws; ++i) {
    const sweep::Draw d = sweep::draw_scenario(20, i);
    ++kinds[static_cast<std::size_t>(d.disturbance)];
    disturbed += d.disturbance != sweep::Disturbance::kNone ? 1 : 0;
    const tactile::rig::Scenario s =
        tactile::rig::parse_scenario(sweep::scenario_yaml(d), "drawn.yaml");
    const tactile::rig::DisturbanceParams& w = s.world.disturbance;
    const auto& start = s.disturbance_start;
    const double weight = d.mass_kg * 9.81;
    switch (d.disturbance) {
      case sweep::Disturbance::kPullStep:
      case sweep::Disturbance::kPullRamp:
        EXPECT_EQ(w.pull.force_n, d.pull_n);
        EXPECT_GE(d.pull_n, 0.5 * weight - 1e-6);
        EXPECT_LE(d.pull_n, 2.0 * weight + 1e-6);
        EXPECT_TRUE(within(d.pull_duration_s, sweep::kPullDurationS));
        EXPECT_EQ(w.pull.duration_s, d.pull_duration_s);
        EXPECT_EQ(w.pull.ramp_s, d.pull_ramp_s);
        EXPECT_EQ(d.pull_ramp_s > 0, d.disturbance == sweep::Disturbance::kPullRamp);
        EXPECT_NEAR(tactile::norm(w.pull.direction), 1.0, 1e-12);
        EXPECT_LE(w.pull.direction.z, 1e-12) << "horizontal or down";
        EXPECT_EQ(start[0].stage, "TRANSPORT");
        EXPECT_EQ(start[0].after_s, d.after_s);
        break;
      case sweep::Disturbance::kMassStep:
        EXPECT_EQ(w.mass_step.added_kg, d.added_kg);
        EXPECT_GE(d.added_kg, 0.5 * d.mass_kg - 1e-5);
        EXPECT_LE(d.added_kg, 2.0 * d.mass_kg + 1e-5);
        EXPECT_EQ(start[1].stage, "TRANSPORT");
        break;
      case sweep::Disturbance::kKnock:
        EXPECT_EQ(w.knock.impulse_ns, d.impulse_ns);
        EXPECT_GE(d.impulse_ns, 0.05 * d.mass_kg - 1e-7);
        EXPECT_LE(d.impulse_ns, 0.3 * d.mass_kg + 1e-7);
        EXPECT_EQ(w.knock.duration_s, sweep::kKnockDurationS);
        EXPECT_EQ(start[2].stage, "TRANSPORT");
        break;
      case sweep::Disturbance::kNone:
        EXPECT_EQ(w.pull.force_n + w.mass_step.added_kg + w.knock.impulse_ns, 0.0);
        break;
    }
    if (d.disturbance != sweep::Disturbance::kNone) {
      EXPECT_TRUE(within(d.after_s, sweep::kDisturbanceAfterS)) << d.after_s;
    }
    EXPECT_EQ(s.world.cap.crush_force_n, d.crush_force_n);
    if (d.crush_force_n > 0) {
      ++fragile;
      // 2 to 6 times the least holding force of this scenario, its disturbance included.
      const double need = tactile::rig::hold_need(s.world, 2.5).grip_needed_n;
      EXPECT_GE(d.crush_force_n, 2.0 * need - 1e-4) << i;
      EXPECT_LE(d.crush_force_n, 6.0 * need + 1e-4) << i;
    }
  }
  // Binomial: a third of 1000 has a standard deviation of 15, a fifth 13, a twelfth 9.
  EXPECT_NEAR(static_cast<double>(disturbed), kDraws / 3.0, 50.0);
  EXPECT_NEAR(static_cast<double>(fragile), kDraws / 5.0, 40.0);
  for (std::size_t k = 1; k < kinds.size(); ++k)
    EXPECT_NEAR(static_cast<double>(kinds[k]), kDraws / 12.0, 30.0) << k;
  EXPECT_STREQ(sweep::to_string(sweep::Disturbance::kPullRamp), "pull_ramp");
}

// The disturbances come from their own generator: every other value of a scenario, and so its
// file without the new keys, is the draw from before they were drawn (the seed-20 files of
// 18f4c77, as rig --sweep wrote them there, FNV-1a 64 over the 40 files in order).
std::string without_disturbance(std::string y) {
  std::string out;
  std::size_t at = 0;
  while (at < y.size()) {
    const std::size_t end = y.find('\n', at) + 1;
    const std::string line = y.substr(at, end - at);
    at = end;
    if (line.rfind("disturbance:", 0) == 0 || line.rfind("# Disturbance", 0) == 0 ||
        line.rfind("# Fragile", 0) == 0)
      continue;
    out += line;
  }
  const std::size_t crush = out.find("crush_force_n: ");
  if (crush != std::string::npos) out.erase(crush, out.find(", ", crush) + 2 - crush);
  return out;
}

// `--sensor feelers`: every scenario file names the feeler element and is otherwise the draw's,
// byte for byte; "rig" leaves the file as drawn; other names are refused (with the sets' names:
// Sweep.UsageErrorsExit2).
TEST(SweepDraw, TheSensorSetChangesTheSensorAndNothingElse) {
  for (std::uint64_t i = 0; i < 40; ++i) {
    const sweep::Draw drawn = sweep::draw_scenario(20, i);
    EXPECT_EQ(drawn.sensor, sweep::SensorSet::kRig);
    sweep::Draw rig = drawn;
    rig.sensor = *sweep::sensor_set_from_string("rig");
    EXPECT_EQ(sweep::scenario_yaml(rig), sweep::scenario_yaml(drawn));
    sweep::Draw feelers = drawn;
    feelers.sensor = *sweep::sensor_set_from_string("feelers");
    const std::string yaml = sweep::scenario_yaml(feelers, 12.5);
    const std::string line = "sensor: {element_model: feelers}\n";
    const auto at = yaml.find(line);
    ASSERT_NE(at, std::string::npos) << yaml;
    EXPECT_EQ(std::string(yaml).erase(at, line.size()), sweep::scenario_yaml(drawn, 12.5));
    const tactile::rig::Scenario s = tactile::rig::parse_scenario(yaml, "drawn.yaml");
    EXPECT_EQ(s.optics.element_model, tactile::rig::ElementModel::kFeelers);
    EXPECT_EQ(tactile::rig::parse_scenario(sweep::scenario_yaml(drawn), "drawn.yaml")
                  .optics.element_model,
              tactile::rig::ElementModel::kGaussian);
  }
  for (const char* bad : {"", "feeler", "gaussian", "Feelers"})
    EXPECT_FALSE(sweep::sensor_set_from_string(bad).has_value()) << "accepted '" << bad << "'";
}

// `--sensor drawn` (docs/slip.md, "The drawn sensor"): a sensor per scenario from a generator of
// its own, each value in its documented range and stated exactly by the file; the file is the
// rig set's with the camera's shot noise, a fingertip line and a sensor line added, nothing else.
TEST(SweepDraw, TheDrawnSensorLiesInItsRangesAndChangesTheSensorAndNothingElse) {
  const tactile::rig::SensorOpticsParams rig_optics;
  int feelers = 0;
  int shot = 0;
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    for (std::uint64_t i = 0; i < 50; ++i, ++n) {
      const sweep::Draw d = sweep::draw_scenario(seed, i);
      const sweep::DrawnSensor& ds = d.drawn_sensor;
      EXPECT_TRUE(within(ds.normal_stiffness_n_per_mm, sweep::kStiffnessNPerMm))
          << seed << " " << i;
      EXPECT_TRUE(within(ds.spot_scale, sweep::kSpotScale)) << seed << " " << i;
      EXPECT_TRUE(ds.shot_noise_gain == 0 || within(ds.shot_noise_gain, sweep::kShotNoiseGain));
      EXPECT_TRUE(within(ds.normal_curve_error, sweep::kCurveError));
      EXPECT_TRUE(within(ds.shear_curve_error, sweep::kCurveError));
      EXPECT_TRUE(within(ds.layout_offset_x_px, sweep::kLayoutOffsetPx));
      EXPECT_TRUE(within(ds.layout_offset_y_px, sweep::kLayoutOffsetPx));
      feelers += ds.feelers ? 1 : 0;
      shot += ds.shot_noise_gain > 0 ? 1 : 0;

      sweep::Draw drawn = d;
      drawn.sensor = *sweep::sensor_set_from_string("drawn");
      std::string yaml = sweep::scenario_yaml(drawn, 12.5);
      const tactile::rig::Scenario sc = tactile::rig::parse_scenario(yaml, "drawn.yaml");
      EXPECT_EQ(sc.optics.element_model, ds.feelers ? tactile::rig::ElementModel::kFeelers
                                                    : tactile::rig::ElementModel::kGaussian);
      EXPECT_EQ(sc.world.fingertip.normal_stiffness_npm, ds.normal_stiffness_n_per_mm * 1000.0);
      EXPECT_NEAR(sc.optics.spot_sigma_min_px, rig_optics.spot_sigma_min_px * ds.spot_scale, 1e-4);
      EXPECT_NEAR(sc.optics.spot_sigma_max_px, rig_optics.spot_sigma_max_px * ds.spot_scale, 1e-4);
      EXPECT_EQ(sc.camera.shot_noise_gain, ds.shot_noise_gain);
      EXPECT_EQ(sc.optics.normal_curve_error, ds.normal_curve_error);
      EXPECT_EQ(sc.optics.shear_curve_error, ds.shear_curve_error);
      EXPECT_EQ(sc.optics.layout_offset_px.x, ds.layout_offset_x_px);
      EXPECT_EQ(sc.optics.layout_offset_px.y, ds.layout_offset_y_px);
      // Less the drawn sensor's text, the rig set's file.
      for (const char* line : {"fingertip: {", "sensor: {"}) {
        const auto at = yaml.find(line);
        ASSERT_NE(at, std::string::npos) << yaml;
        yaml.erase(at, yaml.find('\n', at) + 1 - at);
      }
      if (ds.shot_noise_gain > 0) {
        const std::string gain = fmt::format("shot_noise_gain: {}, ", ds.shot_noise_gain);
        const auto at = yaml.find(gain);
        ASSERT_NE(at, std::string::npos) << yaml;
        yaml.erase(at, gain.size());
      }
      EXPECT_EQ(yaml, sweep::scenario_yaml(d, 12.5));
    }
  }
  // Their shares, 500 draws: binomial standard deviation about 0.022.
  EXPECT_NEAR(static_cast<double>(feelers) / n, sweep::kFeelerShare, 0.08);
  EXPECT_NEAR(static_cast<double>(shot) / n, sweep::kShotNoiseShare, 0.08);
  // The table says the element model of every set, the rest only for the drawn one (a failed
  // run's row holds the draw's cells alone).
  sweep::Draw d = sweep::draw_scenario(20, 3);
  EXPECT_EQ(sweep::failed_row(d, "learned", 1, "").at("element_model"), "gaussian");
  EXPECT_EQ(sweep::failed_row(d, "learned", 1, "").at("spot_scale"), "");
  d.sensor = sweep::SensorSet::kFeelers;
  EXPECT_EQ(sweep::failed_row(d, "learned", 1, "").at("element_model"), "feelers");
  d.sensor = sweep::SensorSet::kDrawn;
  const sweep::Row row = sweep::failed_row(d, "learned", 1, "");
  EXPECT_EQ(row.at("element_model"), d.drawn_sensor.feelers ? "feelers" : "gaussian");
  EXPECT_EQ(row.number("spot_scale"), d.drawn_sensor.spot_scale);
  EXPECT_EQ(row.number("layout_offset_y_px"), d.drawn_sensor.layout_offset_y_px);
}

// `--calibration FILE` (docs/slip.md, "Retraining for your own sensor"): every scenario's camera
// takes the file's image and its sensor section names the file (quoted as YAML quotes it, beside
// the feeler element when both are asked); nothing else of the draw changes. sweep.json says the
// file only when there is one.
TEST(SweepDraw, ALabSensorTakesTheImageAndNamesTheFileAndNothingElse) {
  const tactile::rig::LabSensor lab{"/labs/o'brien/left.yaml", 352, 288, 16};
  for (std::uint64_t i = 0; i < 40; ++i) {
    const sweep::Draw drawn = sweep::draw_scenario(20, i);
    EXPECT_FALSE(drawn.lab_sensor.has_value());
    sweep::Draw labs = drawn;
    labs.lab_sensor = lab;
    std::string yaml = sweep::scenario_yaml(labs, 12.5);
    const std::string line = "sensor: {calibration: '/labs/o''brien/left.yaml'}\n";
    const auto at = yaml.find(line);
    ASSERT_NE(at, std::string::npos) << yaml;
    yaml.erase(at, line.size());
    const std::string image = "width: 352, height: 288, bit_depth: 16";
    const auto camera = yaml.find(image);
    ASSERT_NE(camera, std::string::npos) << yaml;
    yaml.replace(camera, image.size(),
                 "width: 640, height: 480, bit_depth: " + std::to_string(drawn.bit_depth));
    EXPECT_EQ(yaml, sweep::scenario_yaml(drawn, 12.5));
    labs.sensor = sweep::SensorSet::kFeelers;
    EXPECT_NE(sweep::scenario_yaml(labs).find(
                  "sensor: {element_model: feelers, calibration: '/labs/o''brien/left.yaml'}\n"),
              std::string::npos);
  }
  sweep::SweepInfo info;
  info.seed = 20;
  EXPECT_EQ(sweep::info_json(info).find("calibration"), std::string::npos);
  info.calibration = lab.calibration;
  EXPECT_EQ(sweep::parse_info(sweep::info_json(info), "sweep.json").calibration, lab.calibration);
}

TEST(SweepDraw, TheDisturbancesLeaveEveryOtherValueAsItWas) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  bool new_keys = false;
  for (std::uint64_t i = 0; i < 40; ++i) {
    const std::string y = sweep::scenario_yaml(sweep::draw_scenario(20, i));
    const std::string old = without_disturbance(y);
    new_keys = new_keys || old != y;
    for (const unsigned char c : old) {
      hash ^= c;
      hash *= 0x100000001b3ULL;
    }
  }
  EXPECT_TRUE(new_keys) << "some of the 40 are disturbed or fragile";
  EXPECT_EQ(hash, kMainSeed20Hash);
  // Deterministic per (seed, index), whatever was drawn before.
  const sweep::Draw late = sweep::draw_scenario(20, 37);
  for (std::uint64_t i = 0; i < 37; ++i)
    sweep::draw_scenario(20, i);
  EXPECT_EQ(sweep::scenario_yaml(sweep::draw_scenario(20, 37)), sweep::scenario_yaml(late));
}

// The table's disturbance and fragility: the kind and crush force from the draw, broken from the
// report; the summary counts them per kind, and the broken objects.
TEST(SweepTable, DisturbanceAndBrokenComeFromTheDrawAndTheReport) {
  sweep::Draw d = sweep::draw_scenario(1, 0);
  d.disturbance = sweep::Disturbance::kKnock;
  d.crush_force_n = 1.25;
  tactile::rig::Report rep;
  rep.completed = false;
  tactile::rig::CrushTruth crush;
  crush.crush_force_n = 1.25;
  crush.peak_grip_n = 2.5;
  crush.broken = true;
  rep.fragile = crush;
  const sweep::Row row = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(row.at("disturbance"), "knock");
  EXPECT_EQ(row.number("crush_force_N"), 1.25);
  EXPECT_EQ(row.at("broken"), "true");
  EXPECT_EQ(row.number("peak_grip_over_crush"), 2.0);
  const sweep::Row plain =
      sweep::rows_from_report(sweep::draw_scenario(1, 0), tactile::rig::report_json({})).at(0);
  const std::string summary = sweep::summary_markdown({row, plain}, {});
  EXPECT_NE(summary.find("| knock | 1 | 0 | 0 | 0 | 1 | 1 |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("| fragile object broken | 1 of 2 (50.0 %) |"), std::string::npos)
      << summary;
  EXPECT_EQ(sweep::csv_text(sweep::parse_csv(sweep::csv_text({row, plain}), "x.csv")),
            sweep::csv_text({row, plain}));
  // A failed run keeps what was drawn.
  const sweep::Row failed = sweep::failed_row(d, "paper", 1, "boom");
  EXPECT_EQ(failed.at("disturbance"), "knock");
  EXPECT_EQ(failed.at("broken"), "");
}

TEST(SweepTable, CsvReadsBackAsWritten) {
  std::vector<sweep::Row> rows;
  rows.push_back(sweep::failed_row(sweep::draw_scenario(1, 2), "paper", 134, "rig: \"odd\", text"));
  rows.push_back(sweep::failed_row(sweep::draw_scenario(1, 0), "paper", 1, ""));
  const std::string text = sweep::csv_text(rows);
  const std::vector<sweep::Row> back = sweep::parse_csv(text, "x.csv");
  ASSERT_EQ(back.size(), 2U);
  EXPECT_EQ(back[0].at("index"), "0");  // sorted by index
  EXPECT_EQ(back[1].at("error"), "rig: \"odd\", text");
  EXPECT_EQ(back[1].number("exit_status"), 134);
  EXPECT_EQ(sweep::csv_text(back), text);
  EXPECT_THROW(sweep::parse_csv("index,method\n1,paper\n", "bad.csv"), std::runtime_error);
}

// The report's tightness timing fills its columns; null is an empty cell.
TEST(SweepTable, TightnessTimingComesFromTheReport) {
  tactile::rig::Report rep;
  rep.tightened_cycle = 4;
  rep.true_tight_cycle = 3;
  rep.tight_time_error_s = 1.25;
  rep.tight_error_deg = 31.5;
  const sweep::Draw d = sweep::draw_scenario(1, 0);
  const sweep::Row row = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(row.number("tight_cycle_error"), 1);
  EXPECT_EQ(row.number("tight_time_error_s"), 1.25);
  EXPECT_EQ(row.number("tight_error_deg"), 31.5);
  rep.tight_time_error_s.reset();
  rep.tight_error_deg.reset();
  const sweep::Row none = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(none.at("tight_time_error_s"), "");
  EXPECT_EQ(none.at("tight_error_deg"), "");
  const std::string summary = sweep::summary_markdown({row, none}, {});
  EXPECT_NE(summary.find("| tight_time_error_s | 1 | 1.25 |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("| tight_error_deg | 1 | 31.5 |"), std::string::npos) << summary;
}

// The run's detector's incipient lead fills its columns; without an episode the lead is empty.
TEST(SweepTable, IncipientLeadComesFromTheReport) {
  tactile::rig::Report rep;
  rep.slip.incipient_lead_frames = 3;
  rep.slip.incipient_episodes = 5;
  rep.slip.incipient_detected = 4;
  rep.slip_other.incipient_lead_frames = 1;  // the other detector's: not this row's
  const sweep::Draw d = sweep::draw_scenario(1, 0);
  const sweep::Row row = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(row.number("incipient_lead_frames"), 3);
  EXPECT_EQ(row.number("incipient_episodes"), 5);
  EXPECT_EQ(row.number("incipient_detected"), 4);
  rep.slip = {};
  const sweep::Row none = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(none.at("incipient_lead_frames"), "");
  EXPECT_EQ(none.number("incipient_episodes"), 0);
  const std::string summary = sweep::summary_markdown({row, none}, {});
  EXPECT_NE(summary.find("| incipient_lead_frames | 1 | 3 |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("| incipient_detected | 2 |"), std::string::npos) << summary;
}

// The grip's columns from the report's `grip` (docs/slip.md, the sweep's columns): empty when no
// frame was held, and in the summary's scores.
TEST(SweepTable, GripComesFromTheReport) {
  tactile::rig::Report rep;
  rep.grip.held_frames = 120;
  rep.grip.ratio_p50 = 4.5;
  rep.grip.ratio_p95 = 7.25;
  rep.grip.instant_ratio_p50 = 5.5;
  rep.grip.cap_slide_carry_mm = 0.125;
  const sweep::Draw d = sweep::draw_scenario(1, 0);
  const sweep::Row row = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(row.number("grip_ratio_p50"), 4.5);
  EXPECT_EQ(row.number("grip_ratio_p95"), 7.25);
  EXPECT_EQ(row.number("grip_instant_ratio_p50"), 5.5);
  EXPECT_EQ(row.number("cap_slide_carry_mm"), 0.125);
  rep.grip = {};
  const sweep::Row none = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
  EXPECT_EQ(none.at("grip_ratio_p50"), "");
  EXPECT_EQ(none.number("cap_slide_carry_mm"), 0);
  const std::string summary = sweep::summary_markdown({row, none}, {});
  EXPECT_NE(summary.find("| grip_ratio_p50 | 1 | 4.5 |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("| cap_slide_carry_mm | 2 |"), std::string::npos) << summary;
  EXPECT_EQ(sweep::csv_text(sweep::parse_csv(sweep::csv_text({row, none}), "x.csv")),
            sweep::csv_text({row, none}));
}

// The negative cases in the table and the summary: a `case` column from the draw, the report's
// verdict, classifications counted per case and the failed negative scenarios listed by index.
TEST(SweepTable, NegativeCasesAreCountedPerCaseAndTheFailedListed) {
  std::vector<sweep::Row> rows;
  for (std::uint64_t i = 0; i < 10; ++i) {
    const sweep::Draw d = sweep::draw_scenario(3, i);
    tactile::rig::Report rep;
    rep.scenario_case = sweep::to_string(d.scenario_case);
    rep.grasp_classified.emplace("grasp");  // right in a normal case, wrong when the cap is held
    rep.release_classified.emplace("release");  // wrong when the bottle is displaced
    rep.opened_in_air = d.scenario_case == sweep::Case::kBottleDisplaced;
    tactile::rig::judge_negative_case(rep);
    const sweep::Row row = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
    EXPECT_EQ(row.at("case"), sweep::to_string(d.scenario_case));
    EXPECT_EQ(row.at("negative_case_passed"),
              d.scenario_case == sweep::Case::kNormal ? "" : "false");
    rows.push_back(row);
    // A report of another case than the draw's is not this scenario's.
    rep.scenario_case = d.scenario_case == sweep::Case::kCapHeld ? "normal" : "cap_held";
    EXPECT_THROW(sweep::rows_from_report(d, tactile::rig::report_json(rep)), std::runtime_error);
  }
  std::string displaced, held;
  for (const sweep::Row& r : rows) {
    if (r.at("case") == "bottle_displaced") displaced = r.at("index");
    if (r.at("case") == "cap_held") held = r.at("index");
  }
  ASSERT_FALSE(displaced.empty());
  ASSERT_FALSE(held.empty());
  // A failed run has its case too.
  EXPECT_EQ(
      sweep::failed_row(sweep::draw_scenario(3, std::stoull(held)), "paper", 1, "").at("case"),
      "cap_held");
  const std::string summary = sweep::summary_markdown(rows, {});
  EXPECT_NE(summary.find("| normal | 8 | 8 | 8 | 0 | - |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("| bottle_displaced | 1 | 1 | 1 | 1 | 0 of 1 |"), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("| cap_held | 1 | 1 | 1 | 0 | 0 of 1 |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("bottle_displaced failed (index): " + displaced), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("cap_held failed (index): " + held), std::string::npos) << summary;
  EXPECT_EQ(sweep::csv_text(sweep::parse_csv(sweep::csv_text(rows), "x.csv")),
            sweep::csv_text(rows));
}

// Holdable within F2 from the report; the summary counts completion, drops and OVER of the normal
// scenarios apart for the holdable and the others, and lists the others by index.
TEST(SweepTable, HoldableAndNotHoldableAreCountedApart) {
  std::vector<sweep::Row> rows;
  std::vector<std::string> normal;
  for (std::uint64_t i = 0; i < 10; ++i) {
    const sweep::Draw d = sweep::draw_scenario(3, i);
    tactile::rig::Report rep;
    rep.scenario_case = sweep::to_string(d.scenario_case);
    tactile::rig::judge_negative_case(rep);
    rep.hold.grip_needed_n = 0.5;
    rep.hold.grip_allowed_n = i < 7 ? 40.0 : 0.4;
    rep.hold.holdable = i < 7;
    rep.completed = i < 7 && d.scenario_case == sweep::Case::kNormal;
    rep.dropped = i >= 7;
    rep.over_events = i == 0 ? 1 : 0;
    const sweep::Row row = sweep::rows_from_report(d, tactile::rig::report_json(rep)).at(0);
    EXPECT_EQ(row.at("holdable"), i < 7 ? "true" : "false");
    EXPECT_EQ(row.number("grip_needed_N"), 0.5);
    EXPECT_EQ(row.number("grip_allowed_N"), rep.hold.grip_allowed_n);
    if (d.scenario_case == sweep::Case::kNormal) normal.push_back(row.at("index"));
    rows.push_back(row);
  }
  std::size_t normal_holdable = 0;
  for (const std::string& i : normal)
    normal_holdable += std::stoi(i) < 7 ? 1 : 0;
  const std::size_t normal_not = normal.size() - normal_holdable;
  const std::string summary = sweep::summary_markdown(rows, {});
  EXPECT_NE(summary.find(fmt::format(
                "| holdable within F2 | {} | {} | 0 | {} |", normal_holdable, normal_holdable,
                std::find(normal.begin(), normal.end(), "0") != normal.end() ? 1 : 0)),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find(fmt::format("| not holdable within F2 | {} | 0 | {} | 0 |", normal_not,
                                     normal_not)),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("Not holdable within F2 (index, any case): 7, 8, 9"), std::string::npos)
      << summary;
}

// The ideal-sensor recall of the 200 scenarios of seed 20 (docs/slip.md): drawn dashed, their
// sorted curve once carried a dash phase a rounding error short of a dash's end, and the plot
// advanced by nothing for ever (fixed in common/plot). The plot must be written.
TEST(SweepPlot, TheSeed20CurveThatHungIsDrawn) {
  const std::vector<double> ideal_recall{0.7175866495507061,
                                         0.9412568306010929,
                                         0.803921568627451,
                                         0.7378277153558053,
                                         0.8704453441295547,
                                         1,
                                         0.8705357142857143,
                                         0.9514563106796117,
                                         0.7769784172661871,
                                         0.9061371841155235,
                                         0.8283485045513654,
                                         0.983271375464684,
                                         0.964,
                                         0.9066115702479339,
                                         0.7663551401869159,
                                         0.978021978021978,
                                         0.9508771929824561,
                                         0.965042372881356,
                                         0.9210526315789473,
                                         1,
                                         0.9106382978723404,
                                         1,
                                         0.5700636942675159,
                                         0.9452054794520548,
                                         0.9044585987261147,
                                         0.9365482233502538,
                                         0.936046511627907,
                                         0.968503937007874,
                                         0.9565217391304348,
                                         0.9549218031278749,
                                         0.6024734982332155,
                                         0.9979591836734694,
                                         0.8954248366013072,
                                         0.915273132664437,
                                         0.8785425101214575,
                                         0.8333333333333334,
                                         0.7538556446637877,
                                         0.373015873015873,
                                         0.7755359394703657,
                                         0.9607843137254902,
                                         0.7839643652561247,
                                         0.8617511520737328,
                                         0.55,
                                         0.8949152542372881,
                                         0.7679245283018868,
                                         0.7362204724409449,
                                         0.620253164556962,
                                         0.3488372093023256,
                                         0.8744525547445255,
                                         0.5758754863813229,
                                         0.7290015847860539,
                                         0.8235294117647058,
                                         0.9716859716859717,
                                         0.8780487804878049,
                                         0.9411764705882353,
                                         1,
                                         0.7639344262295082,
                                         0.6405835543766578,
                                         0.9090909090909091,
                                         0.7263681592039801,
                                         0.6555740432612313,
                                         0.8501228501228502,
                                         0.9712230215827338,
                                         0.6909620991253644,
                                         0.9084967320261438,
                                         0.9525462962962963,
                                         0.9767441860465116,
                                         0.9203268641470889,
                                         0.8,
                                         1,
                                         1,
                                         1,
                                         0.9644444444444444,
                                         0.9855072463768116,
                                         0.9175257731958762,
                                         0.9183673469387755,
                                         0.7745664739884393,
                                         0.7712177121771218,
                                         0.5747126436781609,
                                         0.7222222222222222,
                                         0.7193877551020408,
                                         0.7582938388625592,
                                         0.8226600985221675,
                                         0.8342059336823735,
                                         0.9047619047619048,
                                         0.9088471849865952,
                                         0.9874213836477987,
                                         0.9969040247678018,
                                         0.7275494672754946,
                                         0.9848484848484849,
                                         0.7889908256880734,
                                         0.7278854254422915,
                                         0.8682926829268293,
                                         0.7768762677484787,
                                         0.8036363636363636,
                                         0.4782608695652174,
                                         0.9777777777777777,
                                         0.9651162790697675,
                                         0.8571428571428571,
                                         0.7682619647355163,
                                         0.9382470119521913,
                                         0.9936842105263158,
                                         0.84375,
                                         0.9800469483568075,
                                         0.926829268292683,
                                         0.7780172413793104,
                                         0.9027431421446384,
                                         0.9907145740815503,
                                         0.9405684754521964,
                                         0.9689922480620154,
                                         0.8576709796672828,
                                         0.7333333333333333,
                                         0.9698492462311558,
                                         0.8586497890295358,
                                         0.9693165969316597,
                                         0.8870056497175142,
                                         0.9522613065326633,
                                         0.9451476793248945,
                                         0.8421052631578947,
                                         0.8248587570621468,
                                         0.9140127388535032,
                                         0.9204545454545454,
                                         0.9867549668874173,
                                         0.8791666666666667,
                                         0.9868421052631579,
                                         0.9903846153846154,
                                         0.9629629629629629,
                                         0.7491821155943293,
                                         0.8671497584541062,
                                         0.9124629080118695,
                                         0.8654545454545455,
                                         0.9763779527559056,
                                         0.4626865671641791,
                                         0.9918032786885246,
                                         0.983402489626556,
                                         0.8851351351351351,
                                         0.9714285714285714,
                                         0.9786476868327402,
                                         0.9015873015873016,
                                         0.8603174603174604,
                                         0.8734177215189873,
                                         0.48936170212765956,
                                         0.9526627218934911,
                                         1,
                                         0.8341121495327103,
                                         0.7602739726027398,
                                         0.9608108108108108,
                                         0.9057815845824411,
                                         0.840867992766727,
                                         0.8961937716262975,
                                         0.909967845659164,
                                         0.8778718258766627,
                                         0.9100346020761245,
                                         0.6557734204793029,
                                         0.9821428571428571,
                                         0.4130879345603272,
                                         0.9898819561551433,
                                         0.9629629629629629,
                                         0.7222222222222222,
                                         0.8421900161030595,
                                         0.5677655677655677,
                                         0.5959595959595959,
                                         0.9852941176470589,
                                         0.9755043227665706,
                                         0.9308823529411765,
                                         0.8427672955974843,
                                         0.9470899470899471,
                                         0.8296703296703297,
                                         0.9309090909090909,
                                         0.825938566552901,
                                         0.8666666666666667,
                                         0.8648648648648649,
                                         0.8421052631578947,
                                         0.8969072164948454,
                                         0.8620689655172413,
                                         0.8230980751604033,
                                         0.9462809917355371,
                                         0.918200408997955,
                                         1,
                                         0.7702702702702703,
                                         0.776595744680851,
                                         1,
                                         0.6949860724233984,
                                         0.9183673469387755,
                                         0.8588410104011887,
                                         0.9247787610619469,
                                         0.8,
                                         0.9113924050632911,
                                         0.935064935064935,
                                         0.9611041405269761,
                                         0.9649390243902439,
                                         0.8058252427184466,
                                         0.9565217391304348,
                                         0.9189944134078212,
                                         0.8816964285714286,
                                         0.7666666666666667,
                                         0.8197802197802198,
                                         0.6717032967032966,
                                         0.9082217973231358,
                                         0.7224489795918367};
  std::vector<sweep::Row> rows;
  for (std::size_t i = 0; i < ideal_recall.size(); ++i) {
    sweep::Row row = sweep::failed_row(sweep::draw_scenario(20, i), "paper", 0, "");
    const auto& c = sweep::columns();
    row.cells[static_cast<std::size_t>(std::find(c.begin(), c.end(), "ideal_recall") - c.begin())] =
        fmt::format("{}", ideal_recall[i]);
    rows.push_back(std::move(row));
  }
  TempDir dir;
  sweep::SweepInfo info;
  info.seed = 20;
  info.scenarios = 200;
  sweep::write_plot(rows, info, dir / "sweep.png");
  EXPECT_GT(fs::file_size(dir / "sweep.png"), 1000U);
}

ProcessResult rig(std::vector<std::string> args) {
  args.insert(args.begin(), kRig);
  return tactile::testing::run(args, std::chrono::seconds(120));
}

std::string read(const fs::path& p) {
  return tactile::util::read_file(p);
}

// Three scenarios cut at 6 s simulated (the fingertips touch and lift the cap by then): each run
// takes about a second.
const std::vector<std::string> kTiny{"--sweep", "3", "--seed", "11", "--max-sim-time", "6"};

std::vector<std::string> tiny(std::vector<std::string> more) {
  std::vector<std::string> a = kTiny;
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

TEST(Sweep, SameSeedGivesTheSameTableWhateverTheJobCountAndEachScenarioRerunsAlone) {
  TempDir dir;
  const ProcessResult one = rig(tiny({"--out", (dir / "one").string(), "--jobs", "1"}));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const ProcessResult three = rig(tiny({"--out", (dir / "three").string(), "--jobs", "3"}));
  ASSERT_EQ(three.exit_code, 0) << three.err;
  const std::string csv = read(dir / "one" / "sweep.csv");
  EXPECT_EQ(csv, read(dir / "three" / "sweep.csv"));
  EXPECT_EQ(read(dir / "one" / "summary.md"), read(dir / "three" / "summary.md"));
  EXPECT_NE(one.out.find("| precision | 3 |"), std::string::npos) << "summary on stdout";
  EXPECT_NE(one.err.find("9/9 runs done"), std::string::npos) << "progress on stderr";
  EXPECT_TRUE(fs::file_size(dir / "one" / "sweep.png") > 1000);

  // One row per scenario and detector, each from its own run.
  const std::vector<sweep::Row> all = sweep::parse_csv(csv, "sweep.csv");
  ASSERT_EQ(all.size(), 9U);
  std::vector<sweep::Row> rows;
  const char* methods[] = {"field", "learned", "paper"};
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].at("method"), methods[i % 3]);
    EXPECT_EQ(all[i].at("index"), std::to_string(i / 3));
    EXPECT_FALSE(all[i].at("precision_without_edges").empty());
    if (all[i].at("method") == "paper") rows.push_back(all[i]);
  }
  EXPECT_NE(one.out.find("## Method `field`: 3 scenarios"), std::string::npos) << one.out;
  EXPECT_NE(one.out.find("## Method `learned`: 3 scenarios"), std::string::npos) << one.out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].at("index"), std::to_string(i));
    EXPECT_EQ(rows[i].at("exit_status"), "0");
    EXPECT_EQ(rows[i].at("end_reason"), "max_time");
    EXPECT_EQ(rows[i].number("sim_time_s"), 6);
    EXPECT_GT(rows[i].number("max_fz_N"), 0.1)
        << "the runs reach the cap: the tables compare scores";
    EXPECT_EQ(rows[i].number("mass_kg"), sweep::draw_scenario(11, i).mass_kg);
  }
  // Any scenario re-runs alone from its file, to the same report.
  const ProcessResult alone =
      rig({"--lockstep", "--scenario", (dir / "one" / "scenarios" / "00001.yaml").string(),
           "--report", (dir / "alone.json").string(), "--slip-detector", "field"});
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  EXPECT_EQ(read(dir / "alone.json"), read(dir / "one" / "reports" / "00001-field.json"));
  EXPECT_NE(read(dir / "alone.json").find("\"detector\": \"field\""), std::string::npos);
}

TEST(Sweep, ThreeShardsMergedEqualOneWholeRun) {
  TempDir dir;
  const ProcessResult whole =
      rig(tiny({"--out", (dir / "whole").string(), "--jobs", "2", "--detectors", "paper"}));
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  std::vector<std::string> merge{"--sweep-merge"};
  for (int k = 1; k <= 3; ++k) {
    const std::string out = (dir / ("shard" + std::to_string(k))).string();
    const ProcessResult r =
        rig(tiny({"--out", out, "--shard", std::to_string(k) + "/3", "--detectors", "paper"}));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(sweep::parse_csv(read(fs::path(out) / "sweep.csv"), out).size(), 1U);
    merge.push_back(out);
  }
  merge.push_back("--out");
  merge.push_back((dir / "merged").string());
  const ProcessResult merged = rig(merge);
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_EQ(read(dir / "merged" / "sweep.csv"), read(dir / "whole" / "sweep.csv"));
  EXPECT_EQ(read(dir / "merged" / "summary.md"), read(dir / "whole" / "summary.md"));
  EXPECT_TRUE(fs::exists(dir / "merged" / "sweep.png"));

  // A shard given twice is refused, naming the scenario, not counted twice.
  const ProcessResult twice = rig({"--sweep-merge", (dir / "shard1").string(),
                                   (dir / "shard1").string(), "--out", (dir / "m2").string()});
  EXPECT_EQ(twice.exit_code, 1);
  EXPECT_NE(twice.err.find("scenario 0 (method paper) is in"), std::string::npos) << twice.err;
  // A shard of another sweep is refused too.
  const ProcessResult other =
      rig({"--sweep", "3", "--seed", "12", "--max-sim-time", "3", "--shard", "2/3", "--out",
           (dir / "other").string(), "--detectors", "paper"});
  ASSERT_EQ(other.exit_code, 0) << other.err;
  const ProcessResult mixed = rig({"--sweep-merge", (dir / "shard1").string(),
                                   (dir / "other").string(), "--out", (dir / "m3").string()});
  EXPECT_EQ(mixed.exit_code, 1);
  EXPECT_NE(mixed.err.find("not shards of one sweep"), std::string::npos) << mixed.err;
}

TEST(Sweep, AFailingRigProcessIsARowWithItsStatusAndLastLine) {
  TempDir dir;
  // A child that fails for scenario 1 and is the real rig for the others.
  const fs::path child = dir / "child.sh";
  {
    std::ofstream f(child);
    f << "#!/bin/sh\n"
         "case \"$3\" in *00001.yaml) echo 'first line' >&2; echo 'rig: it broke' >&2; exit 3;; "
         "esac\n"
         "exec '"
      << kRig << "' \"$@\"\n";
  }
  fs::permissions(child, fs::perms::owner_all);
  sweep::SweepOptions o;
  o.scenarios = 3;
  o.seed = 11;
  o.out = dir / "out";
  o.jobs = 2;
  o.max_sim_time_s = 1;
  o.detectors = {"paper"};
  o.child_program = child.string();
  EXPECT_EQ(sweep::run_sweep(o), 3U);
  const std::vector<sweep::Row> rows =
      sweep::parse_csv(read(dir / "out" / "sweep.csv"), "sweep.csv");
  ASSERT_EQ(rows.size(), 3U);
  EXPECT_EQ(rows[0].at("exit_status"), "0");
  EXPECT_EQ(rows[1].at("exit_status"), "3");
  EXPECT_EQ(rows[1].at("error"), "rig: it broke");
  EXPECT_EQ(rows[1].at("completed"), "");
  EXPECT_EQ(rows[1].number("mass_kg"), sweep::draw_scenario(11, 1).mass_kg);
  EXPECT_EQ(rows[2].at("exit_status"), "0");
  EXPECT_NE(
      read(dir / "out" / "summary.md").find("| rig failed (a row with its exit status) | 1 of 3"),
      std::string::npos);
}

TEST(Sweep, AProgramThatCannotStartIsARowPerScenario) {
  TempDir dir;
  sweep::SweepOptions o;
  o.scenarios = 2;
  o.out = dir / "out";
  o.detectors = {"paper"};
  o.child_program = (dir / "no-such-rig").string();
  EXPECT_EQ(sweep::run_sweep(o), 2U);
  for (const sweep::Row& row : sweep::parse_csv(read(dir / "out" / "sweep.csv"), "sweep.csv")) {
    EXPECT_EQ(row.at("exit_status"), "127");
    EXPECT_NE(row.at("error").find("no-such-rig"), std::string::npos) << row.at("error");
  }
}

// Whether a running sweep reports `progress` on standard error within a minute.
bool wait_for_progress(tactile::testing::Process& p, const std::string& progress) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (p.err_so_far().find(progress) == std::string::npos &&
         std::chrono::steady_clock::now() < deadline && p.running()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return p.err_so_far().find(progress) != std::string::npos;
}

TEST(Sweep, SigintStopsTheChildrenAndWritesWhatIsDone) {
  TempDir dir;
  tactile::testing::Process p({kRig, "--sweep", "6", "--seed", "11", "--max-sim-time", "6",
                               "--jobs", "1", "--out", (dir / "out").string(), "--detectors",
                               "paper"});
  ASSERT_TRUE(wait_for_progress(p, "1/6 runs done")) << p.err_so_far();
  p.signal(SIGINT);
  const ProcessResult r = p.wait(std::chrono::seconds(30));
  ASSERT_FALSE(r.timed_out);
  // A partial table: 128 + SIGINT, so that a script tells it from a finished sweep.
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_NE(r.err.find("sweep: stopped; "), std::string::npos) << r.err;
  const std::vector<sweep::Row> rows =
      sweep::parse_csv(read(dir / "out" / "sweep.csv"), "sweep.csv");
  EXPECT_GE(rows.size(), 1U);
  EXPECT_LT(rows.size(), 6U);
  for (const sweep::Row& row : rows)
    EXPECT_EQ(row.at("exit_status"), "0") << "a stopped child is not a failed scenario";
  EXPECT_NE(read(dir / "out" / "summary.md").find("Stopped by a signal"), std::string::npos);
  // Every scenario file is there to re-run, also those the stop left unrun.
  EXPECT_TRUE(fs::exists(dir / "out" / "scenarios" / "00005.yaml"));
}

TEST(Sweep, ResumeRunsOnlyTheRunsAStopLeftWithoutAReportToTheSameTable) {
  TempDir dir;
  const std::vector<std::string> args{kRig,
                                      "--sweep",
                                      "4",
                                      "--seed",
                                      "11",
                                      "--max-sim-time",
                                      "6",
                                      "--detectors",
                                      "paper",
                                      "--out",
                                      (dir / "cut").string()};
  tactile::testing::Process p(args);
  ASSERT_TRUE(wait_for_progress(p, "2/4 runs done")) << p.err_so_far();
  p.signal(SIGTERM);
  // Stopped before it was done: 143 after writing what it has (docs/reliability.md, "Signals").
  ASSERT_EQ(p.wait(std::chrono::seconds(30)).exit_code, 143);
  ASSERT_TRUE(sweep::parse_info(read(dir / "cut" / "sweep.json"), "sweep.json").stopped);
  const std::size_t done = sweep::parse_csv(read(dir / "cut" / "sweep.csv"), "sweep.csv").size();
  ASSERT_GE(done, 2U);
  ASSERT_LT(done, 4U) << "the stop came too late to leave a run to resume";

  std::vector<std::string> resume(args.begin() + 1, args.end());
  resume.push_back("--resume");
  const ProcessResult resumed = rig(resume);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find(fmt::format("resuming: {} runs kept from their reports, {} to run",
                                         done, 4 - done)),
            std::string::npos)
      << resumed.err;
  EXPECT_FALSE(sweep::parse_info(read(dir / "cut" / "sweep.json"), "sweep.json").stopped);
  const ProcessResult whole =
      rig({"--sweep", "4", "--seed", "11", "--max-sim-time", "6", "--detectors", "paper", "--jobs",
           "2", "--out", (dir / "whole").string()});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_EQ(read(dir / "cut" / "sweep.csv"), read(dir / "whole" / "sweep.csv"));
  EXPECT_EQ(read(dir / "cut" / "summary.md"), read(dir / "whole" / "summary.md"));

  // The reports of another sweep's scenario are not kept: scenario 0 of seed 12 runs again.
  const ProcessResult other =
      rig({"--sweep", "4", "--seed", "12", "--max-sim-time", "6", "--detectors", "paper", "--shard",
           "1/4", "--resume", "--out", (dir / "cut").string()});
  ASSERT_EQ(other.exit_code, 0) << other.err;
  EXPECT_NE(other.err.find("resuming: 0 runs kept from their reports, 1 to run"), std::string::npos)
      << other.err;

  // Nor the reports of another grip (the scenario files are the same): the whole sweep runs
  // again with the margin grip, and resumed with the grip they had, all of them are kept.
  const std::vector<std::string> margin{"--sweep",
                                        "4",
                                        "--seed",
                                        "11",
                                        "--max-sim-time",
                                        "6",
                                        "--detectors",
                                        "paper",
                                        "--grip",
                                        "margin",
                                        "--resume",
                                        "--out",
                                        (dir / "whole").string()};
  const ProcessResult regripped = rig(margin);
  ASSERT_EQ(regripped.exit_code, 0) << regripped.err;
  EXPECT_NE(regripped.err.find("resuming: 0 runs kept from their reports, 4 to run"),
            std::string::npos)
      << regripped.err;
  const ProcessResult again = rig(margin);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.err.find("resuming: 4 runs kept from their reports, 0 to run"), std::string::npos)
      << again.err;
}

// A lab's file the rig's fingertip cannot render (or none) is refused before any scenario runs,
// naming the file: exit 1, nothing written.
TEST(Sweep, ALabCalibrationIsRefusedAtStartUpNamingTheFile) {
  TempDir dir;
  const std::string missing = (dir / "no-such.yaml").string();
  const ProcessResult r =
      rig({"--sweep", "3", "--out", (dir / "x").string(), "--calibration", missing});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(missing + ": cannot open"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "x"));
}

TEST(Sweep, UsageErrorsExit2) {
  TempDir dir;
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"--sweep", "3"},                                                   // no --out
           {"--sweep", "3", "--out", (dir / "x").string(), "--shard", "4/3"},  // K > N
           {"--sweep", "3", "--out", (dir / "x").string(), "--shard", "1-3"},
           {"--sweep-merge", (dir / "x").string(), "--out", (dir / "y").string(), "--resume"},
           {"--sweep", "0", "--out", (dir / "x").string()},
           {"--lockstep"},  // no --scenario
           {"--sweep", "3", "--out", (dir / "x").string(), "--detectors", "paper,wavelet"},
           {"--sweep", "3", "--out", (dir / "x").string(), "--detectors", "paper,paper"},
           {"--sweep", "3", "--out", (dir / "x").string(), "--slip-detector", "field"},
           {"--lockstep", "--scenario", "no-such.yaml", "--slip-detector", "best"},
       }) {
    const ProcessResult r = rig(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << " " << r.err;
  }
  // A sensor set the sweep does not know: the message names the sets and the value.
  for (const char* bad : {"feeler", "gaussian", "Feelers"}) {
    const ProcessResult r = rig({"--sweep", "3", "--out", (dir / "x").string(), "--sensor", bad});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(sweep::kSensorSetNames), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string("'") + bad + "'"), std::string::npos) << r.err;
  }
}

}  // namespace
