// The tactile_calibrate program on real files: PGM frames of the rig's simulated sensor (known
// layout and curves) written by the test, a loads CSV, the calibration files it writes read back
// with the real loader, and the refusal of a bad fit (status, message, nothing written).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "calibrate_scene.hpp"
#include "process.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/pgm.hpp"

namespace tactile {
namespace {

using ::testing::HasSubstr;
using testing::calib::RigSensor;
using testing::calib::shear_mm;

const std::string kCalibrate = TACTILE_CALIBRATE_PATH;

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

std::string describe(const testing::ProcessResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\nstdout:\n" + r.out + "\nstderr:\n" + r.err;
}

// Frames of the rig's sensor on disk: references, a light press, and frames under known loads
// with the loads CSV that names them.
class CalibrateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < 8; ++i) {
      const std::string name = "ref" + std::to_string(i) + ".pgm";
      util::write_pgm(dir_ / name, sensor_.pressed(0.0).view());
      references_.push_back((dir_ / name).string());
    }
    for (int i = 0; i < 2; ++i) {
      const std::string name = "press" + std::to_string(i) + ".pgm";
      util::write_pgm(dir_ / name, sensor_.pressed(0.3).view());
      presses_.push_back((dir_ / name).string());
    }
    // Every element sees 9 normal loads and 7 shear loads along x and y over the frames.
    const double fz[] = {0.1, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0};
    const double fs[] = {-0.25, -0.15, -0.05, 0.0, 0.05, 0.15, 0.25};
    const Calibration& t = sensor_.truth();
    std::string loads = "frame,element,fz_N,fx_N,fy_N\n";
    std::filesystem::create_directory(dir_ / "loaded");
    for (std::size_t j = 0; j < 14; ++j) {
      std::vector<rig::ElementLoad> l(41);
      const std::string name = "loaded/f" + std::to_string(j) + ".pgm";
      for (std::size_t k = 0; k < 41; ++k) {
        const double z = fz[(k + j) % 9];
        const double x = fs[(k + 2 * j) % 7];
        const double y = fs[(3 * k + j) % 7];
        l[k] = {z, shear_mm(t, x), shear_mm(t, y)};
        loads += name + "," + std::to_string(t.elements[k].id) + "," + std::to_string(z) + "," +
                 std::to_string(x) + "," + std::to_string(y) + "\n";
      }
      util::write_pgm(dir_ / name, sensor_.frame(l).view());
    }
    write_text(dir_ / "loads.csv", loads);
  }

  std::vector<std::string> with_references(std::vector<std::string> args) const {
    for (const auto& r : references_) {
      args.push_back("--reference");
      args.push_back(r);
    }
    return args;
  }

  testing::ProcessResult layout(const std::string& out) {
    std::vector<std::string> args{kCalibrate, "layout"};
    args.insert(args.end(), presses_.begin(), presses_.end());
    args = with_references(args);
    for (const char* a : {"--sensor-id", "left", "--mm-per-px", "0.025", "--radius", "14",
                          "--rings", "1,8,16,16", "--ring-polar-deg", "0,10,20,30"})
      args.emplace_back(a);
    args.insert(args.end(), {"-o", out, "--marks", (dir_ / "marks.pgm").string()});
    return testing::run(args, std::chrono::seconds(60));
  }

  testing::ProcessResult measure(const std::string& layout_file, const std::string& out) {
    return testing::run(with_references({kCalibrate, "measure", "--calibration", layout_file,
                                         "--loads", (dir_ / "loads.csv").string(), "-o", out}),
                        std::chrono::seconds(60));
  }

  testing::ProcessResult fit(const std::string& layout_file, const std::string& samples,
                             const std::string& out) {
    return testing::run(
        {kCalibrate, "fit", "--calibration", layout_file, "--samples", samples, "-o", out},
        std::chrono::seconds(60));
  }

  RigSensor sensor_{8, 5};
  testing::TempDir dir_;
  std::vector<std::string> references_;
  std::vector<std::string> presses_;
};

TEST_F(CalibrateCli, LayoutMeasureFitWriteACalibrationThatLoadsAndMatchesTheTruth) {
  const std::string lay = (dir_ / "layout.yaml").string();
  const auto l = layout(lay);
  ASSERT_EQ(l.exit_code, 0) << describe(l);
  EXPECT_THAT(l.out, HasSubstr("41 elements in 4 rings (1, 8, 16, 16)"));
  const Calibration& t = sensor_.truth();
  {
    const Calibration c = config::load_calibration(lay);
    ASSERT_EQ(c.elements.size(), 41u);
    EXPECT_EQ(c.sensor_id, "left");
    EXPECT_EQ(c.width, 640);
    EXPECT_EQ(c.bit_depth, 8);
    for (std::size_t i = 0; i < 41; ++i) {
      EXPECT_EQ(c.elements[i].id, t.elements[i].id);
      EXPECT_LT(norm(c.elements[i].zero_px - t.elements[i].zero_px), 0.05) << i;
      EXPECT_LT(norm(c.elements[i].normal - t.elements[i].normal), 1e-3) << i;
    }
  }
  const Image marks = util::read_pgm(dir_ / "marks.pgm");
  EXPECT_EQ(marks.width(), 640);
  EXPECT_EQ(marks.height(), 480);

  const std::string samples = (dir_ / "samples.csv").string();
  const auto m = measure(lay, samples);
  ASSERT_EQ(m.exit_code, 0) << describe(m);
  const std::string csv = read_text(samples);
  EXPECT_EQ(csv.rfind("element,fz_N,G,", 0), 0u) << csv.substr(0, 200);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 14 * 41);

  const std::string cal = (dir_ / "left.yaml").string();
  const auto f = fit(lay, samples, cal);
  ASSERT_EQ(f.exit_code, 0) << describe(f);
  // The report: one line per element for each curve, and the totals with the limit.
  EXPECT_THAT(f.out, HasSubstr("normal curve F_z = g(G): G ["));
  EXPECT_THAT(f.out, HasSubstr("shear curve F = f(u): mm ["));
  EXPECT_THAT(f.out, HasSubstr("(limit: RMS 0.1 N per element)"));
  EXPECT_THAT(f.out, HasSubstr("(limit: RMS 0.0125 N per element)"));
  const Calibration c = config::load_calibration(cal);
  ASSERT_EQ(c.elements.size(), 41u);
  EXPECT_EQ(c.elements[7].zero_px.x, config::load_calibration(lay).elements[7].zero_px.x);
  for (int i = 0; i <= 20; ++i) {
    const double G = 700 + (13300 - 700) * i / 20.0;
    EXPECT_NEAR(c.normal_curve(G), t.normal_curve(G), 0.04) << "G " << G;
    const double u = 0.054 * i / 20.0;
    EXPECT_NEAR(c.shear_curve(u), t.shear_curve(u), 0.01) << "u " << u;
  }
}

TEST_F(CalibrateCli, RefusesABadFitNamingTheElementAndWritesNothing) {
  const std::string lay = (dir_ / "layout.yaml").string();
  ASSERT_EQ(layout(lay).exit_code, 0);
  const std::string samples = (dir_ / "samples.csv").string();
  ASSERT_EQ(measure(lay, samples).exit_code, 0);

  // Element 12 reads 40 % more G than the others for the same load: monotone, but one curve
  // cannot fit it.
  std::istringstream in(read_text(samples));
  std::string line;
  std::string edited;
  int changed = 0;
  while (std::getline(in, line)) {
    if (line.rfind("12,", 0) == 0) {
      const auto a = line.find(',', 3);      // after fz_N
      const auto b = line.find(',', a + 1);  // after G
      const double G = std::stod(line.substr(a + 1, b - a - 1));
      line = line.substr(0, a + 1) + std::to_string(1.4 * G) + line.substr(b);
      ++changed;
    }
    edited += line + "\n";
  }
  ASSERT_EQ(changed, 14);
  const std::string bad = (dir_ / "bad.csv").string();
  write_text(bad, edited);

  const std::string cal = (dir_ / "left.yaml").string();
  const auto f = fit(lay, bad, cal);
  EXPECT_EQ(f.exit_code, 1) << describe(f);
  std::printf("refusal: %s", f.err.c_str());
  EXPECT_THAT(f.err, HasSubstr("tactile_calibrate: " + bad +
                               ": normal curve: the fit error is "
                               "too large: element 12 has RMS"));
  EXPECT_THAT(f.err, HasSubstr("--max-rms-normal"));
  EXPECT_THAT(f.err, HasSubstr(cal + " not written"));
  EXPECT_FALSE(std::filesystem::exists(cal));
  // The report still shows every element's error, so the bad one can be found.
  EXPECT_THAT(f.out, HasSubstr("       12     14"));

  // The same data with a looser limit are accepted.
  const auto loose = testing::run({kCalibrate, "fit", "--calibration", lay, "--samples", bad, "-o",
                                   cal, "--max-rms-normal", "1"},
                                  std::chrono::seconds(60));
  EXPECT_EQ(loose.exit_code, 0) << describe(loose);
  EXPECT_TRUE(std::filesystem::exists(cal));
}

TEST_F(CalibrateCli, RefusesBadInputNamingFileLineAndValue) {
  const std::string lay = (dir_ / "layout.yaml").string();
  ASSERT_EQ(layout(lay).exit_code, 0);
  // An existing output is not replaced without --overwrite.
  const auto again = layout(lay);
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.err, HasSubstr(lay + " exists: give --overwrite to replace it"));

  const std::string bad = (dir_ / "bad.csv").string();
  write_text(bad, "element,fz_N,G\n3,0.5,5000\n4,0.5,oops\n");
  const auto f = fit(lay, bad, (dir_ / "out.yaml").string());
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_THAT(f.err, HasSubstr(bad + ":3: column 'G' must be a finite number, is 'oops'"));

  write_text(bad, "element,fz_N,G\n77,0.5,5000\n");
  const auto unknown = fit(lay, bad, (dir_ / "out.yaml").string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.err, HasSubstr(bad + ":2: element 77 is not in the calibration of 'left'"));

  // A press frame of another size.
  write_text(dir_ / "loads.csv", "frame,element,fz_N\nsmall.pgm,0,0.5\n");
  util::write_pgm(dir_ / "small.pgm", Image(320, 240, PixelFormat::kMono8).view());
  const auto m = measure(lay, (dir_ / "s.csv").string());
  EXPECT_EQ(m.exit_code, 1);
  EXPECT_THAT(m.err, HasSubstr("small.pgm: frame is 320x240 8-bit, the calibration needs "
                               "640x480 8-bit"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.csv"));

  const auto usage = testing::run({kCalibrate, "fit", "--calibration", lay});
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_THAT(usage.err, HasSubstr("(try --help)"));
}

TEST(CalibrateCliHelp, HelpListsTheStepsAndExitsZero) {
  const auto r = testing::run({kCalibrate, "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("layout"));
  EXPECT_THAT(r.out, HasSubstr("measure"));
  EXPECT_THAT(r.out, HasSubstr("fit"));
  const auto f = testing::run({kCalibrate, "fit", "--help"});
  EXPECT_EQ(f.exit_code, 0);
  EXPECT_THAT(f.out, HasSubstr("--max-rms-normal"));
}

// --- the sample calibration set (tests/data/calibration) and its walk-through -----------------

const std::filesystem::path kSample =
    std::filesystem::path(TACTILE_SOURCE_DIR) / "tests/data/calibration";

// The files the generator writes (the set without its walk-through scripts and README).
std::vector<std::filesystem::path> generated_files(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const auto name = e.path().filename().string();
    if (name == "walkthrough.sh" || name == "retrain.sh" || name == "README.md") continue;
    out.push_back(std::filesystem::relative(e.path(), dir));
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(CalibrationSample, IsExactlyWhatTheGeneratorWrites) {
  testing::TempDir dir;
  const auto r = testing::run({TACTILE_MAKE_CALIBRATION_SAMPLE_PATH, dir.path().string()});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const auto written = generated_files(dir.path());
  EXPECT_EQ(written, generated_files(kSample));
  EXPECT_EQ(written.size(), 16u);  // 4 references, a press, 9 loaded frames, loads, truth
  std::uintmax_t bytes = 0;
  for (const auto& f : written) {
    EXPECT_EQ(read_text(dir / f.string()), read_text(kSample / f)) << f;
    bytes += std::filesystem::file_size(kSample / f);
  }
  EXPECT_LT(bytes, 2'000'000u);
}

// docs/calibration.md's walk-through, its exact commands (walkthrough.sh), on a copy of the set:
// 41 elements where the rig put them, curves within 0.03 N (normal) and 0.01 N (shear) of the
// rig's true ones over the loaded range, and the check step's forces near the applied loads.
TEST(CalibrationSample, TheWalkThroughRunsEndToEndAndRecoversTheRigsSensor) {
  testing::TempDir dir;
  std::filesystem::copy(kSample, dir.path(), std::filesystem::copy_options::recursive);
  const auto r =
      testing::run({"/bin/sh", "-c", "cd \"$0\" && PATH=\"$1:$2:$PATH\" exec sh walkthrough.sh",
                    dir.path().string(), std::filesystem::path(kCalibrate).parent_path().string(),
                    std::filesystem::path(TACTILE_EXTRACT_PATH).parent_path().string()},
                   std::chrono::seconds(60));
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_THAT(r.out, HasSubstr("41 elements in 4 rings (1, 8, 16, 16)"));
  EXPECT_THAT(r.out, HasSubstr("frame 0 at 0.000 s: 41 of 41 elements in contact"));

  const Calibration t = config::load_calibration(dir / "truth.yaml");
  const Calibration c = config::load_calibration(dir / "left.yaml");
  ASSERT_EQ(c.elements.size(), 41u);
  for (std::size_t i = 0; i < 41; ++i) {
    EXPECT_EQ(c.elements[i].id, t.elements[i].id);
    EXPECT_LT(norm(c.elements[i].zero_px - t.elements[i].zero_px), 0.05) << i;
    EXPECT_LT(norm(c.elements[i].normal - t.elements[i].normal), 1e-3) << i;
  }
  double worst_normal = 0;
  double worst_shear = 0;
  for (int i = 0; i <= 20; ++i) {
    const double G = 700 + (14000 - 700) * i / 20.0;  // the G of 0.1 to 2 N
    worst_normal = std::max(worst_normal, std::abs(c.normal_curve(G) - t.normal_curve(G)));
    const double u = 0.054 * i / 20.0;  // the u of 0 to 0.25 N
    worst_shear = std::max(worst_shear, std::abs(c.shear_curve(u) - t.shear_curve(u)));
  }
  std::printf("sample set: fitted curves within %.4f N (normal) and %.4f N (shear) of the truth\n",
              worst_normal, worst_shear);
  EXPECT_LT(worst_normal, 0.03);
  EXPECT_LT(worst_shear, 0.01);

  // The check step: the table's forces for loaded/f04.pgm against its rows of loads.csv.
  std::map<std::uint32_t, std::array<double, 3>> applied;
  std::istringstream loads(read_text(dir / "loads.csv"));
  std::string line;
  while (std::getline(loads, line)) {
    if (line.rfind("loaded/f04.pgm,", 0) != 0) continue;
    std::uint32_t id = 0;
    std::array<double, 3> f{};
    ASSERT_EQ(std::sscanf(line.c_str() + 15, "%u,%lf,%lf,%lf", &id, &f[0], &f[1], &f[2]), 4);
    applied[id] = f;
  }
  ASSERT_EQ(applied.size(), 41u);
  std::istringstream table(r.out.substr(r.out.find("frame 0 at")));
  std::getline(table, line);  // title
  std::getline(table, line);  // header
  int rows = 0;
  while (std::getline(table, line)) {
    std::uint32_t id = 0;
    double v[10];
    if (std::sscanf(line.c_str(), "%u %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &id, &v[0], &v[1],
                    &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9]) != 11)
      continue;
    ASSERT_TRUE(applied.count(id)) << line;
    EXPECT_NEAR(v[9], applied[id][0], 0.03) << line;  // fz_N
    EXPECT_NEAR(v[7], applied[id][1], 0.01) << line;  // fx_N
    EXPECT_NEAR(v[8], applied[id][2], 0.01) << line;  // fy_N
    ++rows;
  }
  EXPECT_EQ(rows, 41);
}

// "Retraining for your own sensor" (docs/calibration.md, docs/slip.md), its exact commands
// (retrain.sh) after the walk-through's: the sweep's scenarios and reports are the fitted file's
// sensor (its image, named in the scenario file and the report), and slip_train writes a model
// that says it was trained on that file.
TEST(CalibrationSample, TheRetrainingWalkThroughRunsTheRigOnTheFittedSensor) {
  testing::TempDir dir;
  std::filesystem::copy(kSample, dir.path(), std::filesystem::copy_options::recursive);
  std::string path;
  for (const char* program :
       {TACTILE_CALIBRATE_PATH, TACTILE_EXTRACT_PATH, TACTILE_RIG_PATH, TACTILE_SLIP_TRAIN_PATH})
    path += std::filesystem::path(program).parent_path().string() + ":";
  const auto r = testing::run(
      {"/bin/sh", "-c", "cd \"$0\" && PATH=\"$1$PATH\" && sh walkthrough.sh && sh retrain.sh",
       dir.path().string(), path},
      std::chrono::seconds(240));
  ASSERT_EQ(r.exit_code, 0) << describe(r);

  const std::filesystem::path fitted = std::filesystem::absolute(dir / "left.yaml");
  const Calibration c = config::load_calibration(fitted);
  const std::string image = "width: " + std::to_string(c.width) +
                            ", height: " + std::to_string(c.height) +
                            ", bit_depth: " + std::to_string(c.bit_depth);
  for (const char* n : {"00000", "00001"}) {
    const std::string scenario = read_text(dir / "sweep/scenarios" / (std::string(n) + ".yaml"));
    EXPECT_THAT(scenario, HasSubstr(image)) << scenario;
    EXPECT_THAT(scenario, HasSubstr("calibration: '" + fitted.string() + "'")) << scenario;
    const std::string report =
        read_text(dir / "sweep/reports" / (std::string(n) + "-learned.json"));
    EXPECT_THAT(report, HasSubstr("\"calibration\": \"" + fitted.string() + "\"")) << report;
    EXPECT_THAT(report, HasSubstr("\"width\": " + std::to_string(c.width))) << report;
    EXPECT_THAT(report, HasSubstr("\"end_reason\"")) << report;
  }
  const std::string csv = read_text(dir / "sweep/sweep.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3) << csv;  // header and two runs
  EXPECT_THAT(read_text(dir / "sweep/sweep.json"), HasSubstr(fitted.string()));

  const std::string model = read_text(dir / "slip_model.inc");
  EXPECT_THAT(model, HasSubstr("--calibration " + fitted.string()));
  EXPECT_THAT(model, HasSubstr("decision"));

  // The same training in two shards: each shard's runs render the file, and the rows fit to the
  // same model.
  const std::vector<std::string> training{TACTILE_SLIP_TRAIN_PATH,
                                          "--calibration",
                                          fitted.string(),
                                          "--seeds",
                                          "105",
                                          "--scenarios",
                                          "2",
                                          "--max-time",
                                          "6",
                                          "--trees",
                                          "4",
                                          "--depth",
                                          "3",
                                          "--jobs",
                                          "2"};
  std::vector<std::string> fit{
      TACTILE_SLIP_TRAIN_PATH,        "--trees",  "4", "--depth", "3", "--out",
      (dir / "sharded.inc").string(), "--rows-in"};
  for (const char* shard : {"1/2", "2/2"}) {
    std::vector<std::string> args = training;
    const std::string rows = (dir / (std::string("rows-") + shard[0])).string();
    args.insert(args.end(), {"--shard", shard, "--rows-out", rows});
    const auto s = testing::run(args, std::chrono::seconds(60));
    ASSERT_EQ(s.exit_code, 0) << describe(s);
    EXPECT_THAT(read_text(rows).substr(0, 400), HasSubstr(fitted.string()));
    fit.push_back(rows);
  }
  const auto f = testing::run(fit, std::chrono::seconds(60));
  ASSERT_EQ(f.exit_code, 0) << describe(f);
  EXPECT_EQ(read_text(dir / "sharded.inc"), model);
}

}  // namespace
}  // namespace tactile
