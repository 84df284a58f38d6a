// tactile_extract as a user runs it (docs/calibration.md): the real program, real files.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "process.hpp"
#include "tactile/config/calibration_file.hpp"

namespace tactile {
namespace {

using nlohmann::json;
using testing::run;
using testing::TempDir;

const std::filesystem::path kData =
    std::filesystem::path(TACTILE_SOURCE_DIR) / "tests/data/extract";
const std::string kExtract = TACTILE_EXTRACT_PATH;

std::vector<std::string> base_args(const std::filesystem::path& set, int references) {
  std::vector<std::string> a{kExtract, "--calibration", (set / "calibration.yaml").string()};
  for (int i = 0; i < references; ++i) {
    a.push_back("--reference");
    a.push_back((set / ("reference-" + std::to_string(i) + ".pgm")).string());
  }
  return a;
}

std::vector<json> lines(const std::string& text) {
  std::vector<json> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    out.push_back(json::parse(line));
  return out;
}

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void expect_same_numbers(const json& a, const json& b, const std::string& where) {
  ASSERT_EQ(a.type(), b.type()) << where;
  if (a.is_object()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (auto it = a.begin(); it != a.end(); ++it) {
      ASSERT_TRUE(b.contains(it.key())) << where << "." << it.key();
      expect_same_numbers(it.value(), b[it.key()], where + "." + it.key());
    }
  } else if (a.is_array()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (std::size_t i = 0; i < a.size(); ++i)
      expect_same_numbers(a[i], b[i], where + "[" + std::to_string(i) + "]");
  } else if (a.is_number()) {
    const double x = a.get<double>();
    const double y = b.get<double>();
    EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(x))) << where;
  } else {
    EXPECT_EQ(a, b) << where;
  }
}

struct SetCase {
  const char* dir;
  int references;
  int frames;
};

class ExtractSample : public ::testing::TestWithParam<SetCase> {};

TEST_P(ExtractSample, ReferenceEstimatorMatchesTheBundledOutput) {
  const SetCase c = GetParam();
  const auto set = kData / c.dir;
  auto args = base_args(set, c.references);
  args.push_back("--estimator");
  args.push_back("thresholded");
  for (int f = 0; f < c.frames; ++f)
    args.push_back((set / ("frame-" + std::to_string(f) + ".pgm")).string());
  const auto r = run(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto got = lines(r.out);
  const auto want = lines(read(set / "expected-thresholded.jsonl"));
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    expect_same_numbers(got[i], want[i], "frame " + std::to_string(i));
}

TEST_P(ExtractSample, DefaultEstimatorFindsTheTrueSpotsAndFollowsTheCurves) {
  const SetCase c = GetParam();
  const auto set = kData / c.dir;
  const Calibration cal = config::load_calibration(set / "calibration.yaml");
  auto args = base_args(set, c.references);
  args.push_back("--fps");
  args.push_back("50");
  for (int f = 0; f < c.frames; ++f)
    args.push_back((set / ("frame-" + std::to_string(f) + ".pgm")).string());
  const auto r = run(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto got = lines(r.out);
  const json truth = json::parse(read(set / "truth.json"));
  ASSERT_EQ(got.size(), static_cast<std::size_t>(c.frames));
  for (int f = 0; f < c.frames; ++f) {
    const json& frame = got[static_cast<std::size_t>(f)];
    EXPECT_EQ(frame["frame"], f);
    EXPECT_DOUBLE_EQ(frame["time_s"].get<double>(), f / 50.0);
    const json& els = frame["elements"];
    ASSERT_EQ(els.size(), cal.elements.size());
    // Spot i of the truth sits on element i; elements beyond the spots are untouched.
    const json& spots = truth[static_cast<std::size_t>(f)]["spots"];
    for (std::size_t e = 0; e < els.size(); ++e) {
      const json& el = els[e];
      EXPECT_EQ(el["id"], cal.elements[e].id);  // calibration order
      const bool pressed = e < spots.size();
      EXPECT_EQ(el["contact"].get<bool>(), pressed) << "frame " << f << " element " << e;
      if (!pressed) {
        EXPECT_TRUE(el["x_px"].is_null());
        EXPECT_TRUE(el["y_px"].is_null());
        for (const char* k : {"dx_mm", "dy_mm", "ux_mm", "uy_mm", "fx", "fy", "fz"})
          EXPECT_EQ(el[k], 0) << k;
        continue;
      }
      EXPECT_NEAR(el["x_px"].get<double>(), spots[e]["x_px"].get<double>(), 0.15);
      EXPECT_NEAR(el["y_px"].get<double>(), spots[e]["y_px"].get<double>(), 0.15);
      EXPECT_DOUBLE_EQ(el["fz"].get<double>(), cal.normal_curve(el["G"].get<double>()));
      const double ux = el["ux_mm"].get<double>();
      EXPECT_DOUBLE_EQ(ux, (el["x_px"].get<double>() - cal.elements[e].zero_px.x) * cal.mm_per_px);
      EXPECT_DOUBLE_EQ(el["fx"].get<double>(), cal.shear_curve.odd(ux));
    }
  }
  if (c.frames == 6) {
    // Element 0 slides 0.4 px = 0.01 mm per frame from frame 3 on, and stands still before.
    EXPECT_NEAR(got[4]["elements"][0]["dx_mm"].get<double>(), 0.01, 0.003);
    EXPECT_NEAR(got[5]["elements"][0]["dx_mm"].get<double>(), 0.01, 0.003);
    EXPECT_LT(std::abs(got[1]["elements"][0]["dx_mm"].get<double>()), 0.003);
  }
}

INSTANTIATE_TEST_SUITE_P(Sets, ExtractSample,
                         ::testing::Values(SetCase{"mono8", 4, 6}, SetCase{"mono16", 2, 3}),
                         [](const ::testing::TestParamInfo<SetCase>& p) {
                           return std::string(p.param.dir);
                         });

TEST(ExtractSampleData, IsExactlyWhatTheGeneratorWrites) {
  TempDir dir;
  const auto r = run({TACTILE_MAKE_SAMPLE_PATH, dir.path().string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* set : {"mono8", "mono16"}) {
    for (const auto& f : std::filesystem::directory_iterator(dir.path() / set)) {
      const auto name = f.path().filename();
      EXPECT_EQ(read(f.path()), read(kData / set / name)) << set << "/" << name;
    }
  }
}

// --- bad input: non-zero exit, one clear line on standard error, nothing half-written -------

struct Outcome {
  int exit_code;
  std::string out;
  std::string err;
};

Outcome run_args(std::vector<std::string> args) {
  const auto r = run(std::move(args));
  return {r.exit_code, r.out, r.err};
}

void expect_one_line_naming(const Outcome& o, const std::vector<std::string>& words) {
  EXPECT_NE(o.exit_code, 0);
  ASSERT_FALSE(o.err.empty());
  EXPECT_EQ(o.err.find('\n'), o.err.size() - 1) << "more than one line: " << o.err;
  for (const auto& w : words)
    EXPECT_NE(o.err.find(w), std::string::npos) << "'" << w << "' not in: " << o.err;
}

TEST(ExtractErrors, BadCalibrationNamesFileKeyAndElement) {
  TempDir dir;
  std::string text = read(kData / "mono8/calibration.yaml");
  const std::string from = "radius_px: 12\n    zero_px: [33.75";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(), "radius_px: -4\n    zero_px: [33.75");
  std::ofstream(dir / "bad.yaml") << text;
  auto args = base_args(kData / "mono8", 1);
  args[2] = (dir / "bad.yaml").string();
  args.push_back((kData / "mono8/frame-0.pgm").string());
  const Outcome o = run_args(args);
  expect_one_line_naming(o, {"bad.yaml", "elements[1].radius_px", "element id 1", "-4"});
  EXPECT_TRUE(o.out.empty());
}

TEST(ExtractErrors, WrongSizeFrameStopsWithWholeLinesOnly) {
  auto args = base_args(kData / "mono8", 4);
  args.push_back((kData / "mono8/frame-0.pgm").string());
  args.push_back((kData / "mono16/frame-0.pgm").string());  // 16-bit: wrong depth
  args.push_back((kData / "mono8/frame-1.pgm").string());
  const Outcome o = run_args(args);
  expect_one_line_naming(o, {"mono16/frame-0.pgm", "16-bit", "8-bit"});
  const auto got = lines(o.out);  // parses: every line is whole
  ASSERT_EQ(got.size(), 1U);
  EXPECT_EQ(got[0]["frame"], 0);
}

TEST(ExtractErrors, UnreadableAndTruncatedImages) {
  TempDir dir;
  std::string pgm = read(kData / "mono8/frame-0.pgm");
  std::ofstream(dir / "short.pgm", std::ios::binary) << pgm.substr(0, pgm.size() / 2);
  std::ofstream(dir / "text.pgm") << "P2\n2 2\n255\n1 2 3 4\n";
  for (const auto& [file, word] : std::vector<std::pair<std::string, std::string>>{
           {(dir / "short.pgm").string(), "truncated"},
           {(dir / "text.pgm").string(), "P5"},
           {(dir / "missing.pgm").string(), "cannot open"}}) {
    auto args = base_args(kData / "mono8", 1);
    args.push_back(file);
    const Outcome o = run_args(args);
    expect_one_line_naming(o, {file, word});
    EXPECT_TRUE(o.out.empty());
  }
}

TEST(ExtractErrors, LoadedReferenceIsRefused) {
  auto args = base_args(kData / "mono8", 0);
  args.push_back("--reference");
  args.push_back((kData / "mono8/frame-3.pgm").string());  // element 0 pressed
  args.push_back((kData / "mono8/frame-4.pgm").string());
  const Outcome o = run_args(args);
  expect_one_line_naming(o, {"frame-3.pgm", "reference", "element 0"});
  EXPECT_TRUE(o.out.empty());
  // The user can insist.
  args.insert(args.begin() + 1, "--no-reference-check");
  EXPECT_EQ(run_args(args).exit_code, 0);
}

TEST(ExtractErrors, BadOptions) {
  expect_one_line_naming(run_args({kExtract, "--calibration", "x.yaml"}), {"--reference"});
  auto args = base_args(kData / "mono8", 1);
  args.push_back("--fps");
  args.push_back("fast");
  expect_one_line_naming(run_args(args), {"--fps"});
  args = base_args(kData / "mono8", 1);
  args.push_back("--estimator");
  args.push_back("magic");
  expect_one_line_naming(run_args(args), {"--estimator", "magic"});
}

TEST(Extract, HelpAndNoFrames) {
  const Outcome help = run_args({kExtract, "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--calibration"), std::string::npos);
  EXPECT_NE(help.out.find("--reference"), std::string::npos);
  EXPECT_NE(help.out.find("--fps"), std::string::npos);
  // No frames: nothing on standard output, success (calibration and reference are valid).
  const Outcome none = run_args(base_args(kData / "mono8", 2));
  EXPECT_EQ(none.exit_code, 0) << none.err;
  EXPECT_TRUE(none.out.empty());
}

}  // namespace
}  // namespace tactile
