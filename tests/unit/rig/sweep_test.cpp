// The random scenario sweep (docs/slip.md, "The sweep"): the draw over many seeds (no rig runs),
// and tiny sweeps of real child rig processes, cut at a few seconds of simulated time.
#include "tactile/rig/sweep.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/util/files.hpp"

namespace {

namespace fs = std::filesystem;
namespace sweep = tactile::rig::sweep;
using tactile::testing::ProcessResult;
using tactile::testing::TempDir;

constexpr const char* kRig = TACTILE_RIG_PATH;

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
        EXPECT_TRUE(s.controller.empty()) << "the controller's defaults, no tuning";
      }
    }
  }
  // The whole range is drawn from, not a corner of it.
  EXPECT_LT(lowest_mass, 0.0035);
  EXPECT_GT(highest_mass, 0.0795);
  EXPECT_LE(lowest_fps, 61);
  EXPECT_GE(highest_fps, 499);
  EXPECT_EQ(depths, (std::set<int>{8, 16}));
}

TEST(SweepDraw, AScenarioDependsOnlyOnTheSeedAndItsIndex) {
  const sweep::Draw late = sweep::draw_scenario(5, 123);
  for (std::uint64_t i = 0; i < 123; ++i)
    sweep::draw_scenario(5, i);
  EXPECT_EQ(sweep::scenario_yaml(sweep::draw_scenario(5, 123)), sweep::scenario_yaml(late));
  EXPECT_NE(sweep::scenario_yaml(sweep::draw_scenario(6, 123)), sweep::scenario_yaml(late));
  EXPECT_NE(sweep::scenario_yaml(sweep::draw_scenario(5, 124)), sweep::scenario_yaml(late));
}

TEST(SweepTable, CsvReadsBackAsWritten) {
  std::vector<sweep::Row> rows;
  rows.push_back(sweep::failed_row(sweep::draw_scenario(1, 2), 134, "rig: \"odd\", text"));
  rows.push_back(sweep::failed_row(sweep::draw_scenario(1, 0), 1, ""));
  const std::string text = sweep::csv_text(rows);
  const std::vector<sweep::Row> back = sweep::parse_csv(text, "x.csv");
  ASSERT_EQ(back.size(), 2U);
  EXPECT_EQ(back[0].at("index"), "0");  // sorted by index
  EXPECT_EQ(back[1].at("error"), "rig: \"odd\", text");
  EXPECT_EQ(back[1].number("exit_status"), 134);
  EXPECT_EQ(sweep::csv_text(back), text);
  EXPECT_THROW(sweep::parse_csv("index,method\n1,paper\n", "bad.csv"), std::runtime_error);
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
  EXPECT_NE(one.err.find("3/3 done"), std::string::npos) << "progress on stderr";
  EXPECT_TRUE(fs::file_size(dir / "one" / "sweep.png") > 1000);

  const std::vector<sweep::Row> rows = sweep::parse_csv(csv, "sweep.csv");
  ASSERT_EQ(rows.size(), 3U);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].at("index"), std::to_string(i));
    EXPECT_EQ(rows[i].at("method"), "paper");
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
           "--report", (dir / "alone.json").string()});
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  EXPECT_EQ(read(dir / "alone.json"), read(dir / "one" / "reports" / "00001.json"));
}

TEST(Sweep, ThreeShardsMergedEqualOneWholeRun) {
  TempDir dir;
  const ProcessResult whole = rig(tiny({"--out", (dir / "whole").string(), "--jobs", "2"}));
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  std::vector<std::string> merge{"--sweep-merge"};
  for (int k = 1; k <= 3; ++k) {
    const std::string out = (dir / ("shard" + std::to_string(k))).string();
    const ProcessResult r = rig(tiny({"--out", out, "--shard", std::to_string(k) + "/3"}));
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
  const ProcessResult other = rig({"--sweep", "3", "--seed", "12", "--max-sim-time", "3", "--shard",
                                   "2/3", "--out", (dir / "other").string()});
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
  o.child_program = (dir / "no-such-rig").string();
  EXPECT_EQ(sweep::run_sweep(o), 2U);
  for (const sweep::Row& row : sweep::parse_csv(read(dir / "out" / "sweep.csv"), "sweep.csv")) {
    EXPECT_EQ(row.at("exit_status"), "127");
    EXPECT_NE(row.at("error").find("no-such-rig"), std::string::npos) << row.at("error");
  }
}

TEST(Sweep, SigintStopsTheChildrenAndWritesWhatIsDone) {
  TempDir dir;
  tactile::testing::Process p({kRig, "--sweep", "6", "--seed", "11", "--max-sim-time", "6",
                               "--jobs", "1", "--out", (dir / "out").string()});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (p.err_so_far().find("1/6 done") == std::string::npos &&
         std::chrono::steady_clock::now() < deadline && p.running()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_NE(p.err_so_far().find("1/6 done"), std::string::npos) << p.err_so_far();
  p.signal(SIGINT);
  const ProcessResult r = p.wait(std::chrono::seconds(30));
  ASSERT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
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

TEST(Sweep, UsageErrorsExit2) {
  TempDir dir;
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"--sweep", "3"},                                                   // no --out
           {"--sweep", "3", "--out", (dir / "x").string(), "--shard", "4/3"},  // K > N
           {"--sweep", "3", "--out", (dir / "x").string(), "--shard", "1-3"},
           {"--sweep", "0", "--out", (dir / "x").string()},
           {"--lockstep"},  // no --scenario
       }) {
    const ProcessResult r = rig(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << " " << r.err;
  }
}

}  // namespace
