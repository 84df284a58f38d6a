// tactile_calibrate's work on synthetic frames with known truth: the layout found within a
// fraction of a pixel, the curves recovered, and every refusal with its message.
#include "calibrate.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <stdexcept>

#include "calibrate_scene.hpp"
#include "synthetic.hpp"
#include "tactile/config/calibration_file.hpp"

namespace tactile::calibrate {
namespace {

using ::testing::HasSubstr;
using testing::calib::kRingPolarDeg;
using testing::calib::RigSensor;
using testing::calib::shear_mm;

// Runs f, expects a std::runtime_error, returns its message.
template <typename F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no refusal";
  return {};
}

LayoutOptions rig_layout_options() {
  LayoutOptions o;
  o.sensor_id = "left";
  o.mm_per_px = 0.025;
  o.radius_px = 14;
  o.ring_counts = {1, 8, 16, 16};
  o.ring_polar_deg.assign(std::begin(kRingPolarDeg), std::end(kRingPolarDeg));
  return o;
}

// Largest distance between the found and the true position, element by element (same ids).
double max_position_error(const Calibration& found, const Calibration& truth) {
  EXPECT_EQ(found.elements.size(), truth.elements.size());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(found.elements.size(), truth.elements.size()); ++i) {
    const auto& f = found.elements[i];
    const auto& t = truth.elements[i];
    EXPECT_EQ(f.id, t.id);
    worst = std::max(worst, norm(f.zero_px - t.zero_px));
    EXPECT_EQ(f.center_px.x, f.zero_px.x);
    EXPECT_EQ(f.center_px.y, f.zero_px.y);
  }
  return worst;
}

// --- layout -------------------------------------------------------------------------------------

TEST(CalibrateLayout, RigSensorAgainstReferencesWithinHundredthsOfAPixelIdsAndNormalsAsTheRig) {
  for (int depth : {8, 16}) {
    SCOPED_TRACE(depth);
    RigSensor sensor(depth);
    LayoutInput in;
    in.references = sensor.references(16);
    for (int i = 0; i < 8; ++i)
      in.frames.push_back(sensor.pressed(0.3));
    const LayoutResult r = find_layout(in, rig_layout_options());
    const Calibration& c = r.calibration;
    ASSERT_EQ(c.elements.size(), 41u);
    EXPECT_EQ(r.group_counts, (std::vector<int>{1, 8, 16, 16}));
    const double err = max_position_error(c, sensor.truth());
    std::printf("layout (%d-bit, references, 8 frames): largest position error %.4f px\n", depth,
                err);
    EXPECT_LT(err, 0.05);
    double normal_err = 0;
    for (std::size_t i = 0; i < c.elements.size(); ++i) {
      const Vec3 d = c.elements[i].normal - sensor.truth().elements[i].normal;
      normal_err = std::max(normal_err, norm(d));
      EXPECT_EQ(c.elements[i].radius_px, 14.0);
    }
    EXPECT_LT(normal_err, 1e-3);
    // The rig's settings for noise 2: floor max(4, 3 sigma) = 6 gray levels, contact 400/250,
    // grown in proportion to the noise measured above 2 gray levels (as the rig's).
    const double scale = depth == 16 ? 257.0 : 1.0;
    EXPECT_NEAR(r.noise_sigma / scale, 2.0, 0.1);
    EXPECT_NEAR(c.noise_floor / scale, 6.0, 0.3);
    const double noise_scale = std::max(1.0, r.noise_sigma / scale / 2.0);
    EXPECT_DOUBLE_EQ(c.contact_on, 400.0 * scale * noise_scale);
    EXPECT_DOUBLE_EQ(c.contact_off, 250.0 * scale * noise_scale);
    EXPECT_NEAR(c.contact_on / scale, 400.0, 20.0);
    EXPECT_EQ(c.width, 640);
    EXPECT_EQ(c.bit_depth, depth);
    EXPECT_EQ(c.sensor_id, "left");
    for (const FoundElement& e : r.elements)
      EXPECT_EQ(e.frames, 8u);
    // A complete, valid file: it reads back as written.
    const Calibration back = config::parse_calibration(config::format_calibration(c), "layout");
    EXPECT_EQ(back.elements.size(), 41u);
  }
}

// Pixels that never change (the same value in every frame and reference: a region the camera
// does not see, or a simulator that draws noise only where it is measured) carry no noise: they
// once made the noise look ten times smaller than it is, and the noise inside the disks then
// showed as spots (77 "elements" a user found; here, pairs of spots closer than a disk).
TEST(CalibrateLayout, PixelsThatNeverChangeDoNotHideTheNoise) {
  for (auto outside : {RigSensor::Outside::kFrozen, RigSensor::Outside::kLive}) {
    SCOPED_TRACE(outside == RigSensor::Outside::kFrozen ? "frozen" : "live background");
    RigSensor sensor(8, 7, 2.0, outside);
    LayoutInput in;
    in.references = sensor.references(16);
    for (int i = 0; i < 8; ++i)
      in.frames.push_back(sensor.pressed(0.1));
    const LayoutResult r = find_layout(in, rig_layout_options());
    EXPECT_EQ(r.calibration.elements.size(), 41u);
    EXPECT_NEAR(r.noise_sigma, 2.0, 0.15);
    EXPECT_LT(max_position_error(r.calibration, sensor.truth()), 0.05);
  }
}

TEST(CalibrateLayout, ASequenceOfPressesFindsEveryElementWhereItsIncrementIs) {
  RigSensor sensor;
  LayoutInput in;
  in.references = sensor.references(8);
  // Four frames, each pressing every fourth element; one element pressed in two frames.
  for (int part = 0; part < 4; ++part) {
    std::vector<rig::ElementLoad> loads(41);
    for (std::size_t k = 0; k < 41; ++k)
      if (static_cast<int>(k % 4) == part || (k == 5 && part == 0)) loads[k].fz_n = 0.4;
    in.frames.push_back(sensor.frame(loads));
  }
  const LayoutResult r = find_layout(in, rig_layout_options());
  const double err = max_position_error(r.calibration, sensor.truth());
  std::printf("layout (sequence of 4 presses, one frame per element): largest error %.4f px\n",
              err);
  EXPECT_LT(err, 0.1);
  EXPECT_EQ(r.elements[5].frames, 2u);
  EXPECT_EQ(r.elements[6].frames, 1u);
}

TEST(CalibrateLayout, WithoutReferenceOnAVignettedGridInRows) {
  // tests/support's synthetic scene: Gaussian spots at known sub-pixel places on a vignetted
  // background; no reference: the background is estimated from the image.
  testing::SceneOptions so;
  so.vignetting = 0.35;
  so.noise_sigma = 2.0;
  Calibration grid = testing::grid_calibration(so, 7, 5, 60.0, 14.0);
  util::Random rng(11);
  std::vector<testing::Spot> spots;
  for (auto& e : grid.elements) {
    e.zero_px = e.center_px + Vec2{rng.uniform(-3, 3), rng.uniform(-3, 3)};
    spots.push_back({e.zero_px, 120.0, 2.0});
  }
  LayoutInput in;
  for (int i = 0; i < 6; ++i) {
    Image img;
    testing::render(so, spots, rng, img);
    in.frames.push_back(std::move(img));
  }
  LayoutOptions o;
  o.sensor_id = "grid";
  o.mm_per_px = 0.02;
  o.expect = 35;
  o.order = ElementOrder::kRows;
  o.ring_counts = {7, 7, 7, 7, 7};
  const LayoutResult r = find_layout(in, o);
  ASSERT_EQ(r.calibration.elements.size(), 35u);
  double worst = 0;
  for (std::size_t i = 0; i < 35; ++i)
    worst = std::max(worst, norm(r.calibration.elements[i].zero_px - grid.elements[i].zero_px));
  std::printf("layout (no reference, vignetted grid, 6 frames): largest error %.4f px\n", worst);
  EXPECT_LT(worst, 0.05);
  // Automatic radius: 0.45 x the smallest distance, down to a half pixel.
  double dmin = INFINITY;
  for (std::size_t i = 0; i < 35; ++i)
    for (std::size_t j = i + 1; j < 35; ++j)
      dmin = std::min(dmin, norm(grid.elements[i].zero_px - grid.elements[j].zero_px));
  EXPECT_LE(r.calibration.elements[0].radius_px, 0.45 * dmin + 0.05);
  EXPECT_GT(r.calibration.elements[0].radius_px, 0.45 * dmin - 0.6);
  for (const auto& e : r.calibration.elements) {
    EXPECT_EQ(e.normal.z, 1.0);  // no dome model: placeholders
  }
  EXPECT_FALSE(r.dome_normals);
  const Image marks = mark_layout(r);
  EXPECT_EQ(marks.width(), 640);
  EXPECT_EQ(marks.get(static_cast<int>(std::lround(r.calibration.elements[0].zero_px.x)),
                      static_cast<int>(std::lround(r.calibration.elements[0].zero_px.y))),
            255u);
}

TEST(CalibrateLayout, AzimuthOffsetAndMirrorTurnTheOrderAndTheNormals) {
  RigSensor sensor;
  LayoutInput in;
  in.references = sensor.references(4);
  in.frames.push_back(sensor.pressed(0.3));
  in.frames.push_back(sensor.pressed(0.3));
  LayoutOptions o = rig_layout_options();
  o.mirror = true;
  const LayoutResult r = find_layout(in, o);
  // Mirrored: element 1 of ring 1 is the rig's element 8 (azimuth -45 degrees in the image).
  EXPECT_LT(norm(r.calibration.elements[2].zero_px - sensor.truth().elements[8].zero_px), 0.1);
  EXPECT_NEAR(r.elements[2].azimuth_deg, 45.0, 0.1);
  EXPECT_NEAR(r.calibration.elements[2].normal.y,
              std::sin(10 * std::numbers::pi / 180) * std::sin(std::numbers::pi / 4), 1e-3);
}

TEST(CalibrateLayout, RefusesAnotherCountOverlapsRingsAndDust) {
  RigSensor sensor;
  LayoutInput in;
  in.references = sensor.references(4);
  std::vector<rig::ElementLoad> loads(41, rig::ElementLoad{0.3, 0, 0});
  loads[17].fz_n = 0;  // one element not pressed
  in.frames.push_back(sensor.frame(loads));
  EXPECT_THAT(refusal([&] { find_layout(in, rig_layout_options()); }),
              HasSubstr("found 40 elements, expected 41 (--expect)"));

  in.frames.assign(1, sensor.pressed(0.3));
  LayoutOptions o = rig_layout_options();
  o.radius_px = 25;
  const std::string overlap = refusal([&] { find_layout(in, o); });
  EXPECT_THAT(overlap, HasSubstr("overlap"));
  EXPECT_THAT(overlap, HasSubstr("give --radius 22.9 or less"));

  o = rig_layout_options();
  o.ring_counts = {1, 8, 15, 17};
  EXPECT_THAT(refusal([&] { find_layout(in, o); }),
              HasSubstr("the rings found hold 1, 8, 16, 16 elements, --rings says 1, 8, 15, 17"));

  o = rig_layout_options();
  o.ring_polar_deg = {0, 10, 20};
  EXPECT_THAT(refusal([&] { find_layout(in, o); }),
              HasSubstr("--ring-polar-deg gives 3 rings, the layout has 4"));

  // A speck of dust between the rings: one spot too many, named.
  Image dusty = sensor.pressed(0.3);
  for (int y = 398; y <= 402; ++y)
    for (int x = 98; x <= 102; ++x)
      dusty.set(x, y, dusty.get(x, y) + 25);
  in.frames.assign(1, dusty);
  const std::string dust = refusal([&] { find_layout(in, rig_layout_options()); });
  EXPECT_THAT(dust, HasSubstr("found 42 elements, expected 41"));
  EXPECT_THAT(dust, HasSubstr("the weakest at (100.0, 400.0)"));

  // Nothing pressed at all.
  in.frames.assign(1, sensor.pressed(0.0));
  EXPECT_THAT(refusal([&] { find_layout(in, rig_layout_options()); }),
              HasSubstr("found 0 elements, expected 41"));
}

TEST(CalibrateLayout, RefusesADiskThatLeavesTheImage) {
  testing::SceneOptions so;
  util::Random rng(3);
  Image img;
  testing::render(so, {{{10.0, 240.0}, 120.0, 2.0}, {{300.0, 240.0}, 120.0, 2.0}}, rng, img);
  LayoutInput in;
  in.frames.push_back(img);
  LayoutOptions o;
  o.sensor_id = "edge";
  o.mm_per_px = 0.02;
  o.expect = 2;
  o.radius_px = 14;
  EXPECT_THAT(refusal([&] { find_layout(in, o); }),
              HasSubstr("the disk of the element at (10.0, 240.0) with radius 14 px leaves the "
                        "640x480 image"));
}

// --- measure and fit ----------------------------------------------------------------------------

struct LoadedRun {
  std::vector<Image> references;
  std::map<std::string, Image> frames;
  std::vector<LoadRow> loads;
};

// Frames of the rig's sensor under known loads: every element gets a normal load from 0.1 to
// 2 N and shear loads from -0.25 to 0.25 N along x and y, varied from frame to frame.
LoadedRun loaded_run(RigSensor& sensor, int frames) {
  const double fz[] = {0.1, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0};
  const double fs[] = {-0.25, -0.15, -0.05, 0.0, 0.05, 0.15, 0.25};
  LoadedRun run;
  run.references = sensor.references(16);
  const Calibration& t = sensor.truth();
  for (int j = 0; j < frames; ++j) {
    std::vector<rig::ElementLoad> loads(41);
    const std::string name = "f" + std::to_string(j) + ".pgm";
    for (std::size_t k = 0; k < 41; ++k) {
      const double z = fz[(k + static_cast<std::size_t>(j)) % 9];
      const double x = fs[(k + 2 * static_cast<std::size_t>(j)) % 7];
      const double y = fs[(3 * k + static_cast<std::size_t>(j)) % 7];
      loads[k] = {z, shear_mm(t, x), shear_mm(t, y)};
      run.loads.push_back({name, t.elements[k].id, z, true, x, true, y, name});
    }
    run.frames[name] = sensor.frame(loads);
  }
  return run;
}

std::vector<Sample> measure(const Calibration& cal, const LoadedRun& run) {
  return measure_samples(cal, run.references, run.loads,
                         [&run](const std::string& name) { return run.frames.at(name); }, {});
}

// Largest |fitted - true| over [lo, hi].
double curve_error(const PiecewiseLinear& fitted, const PiecewiseLinear& truth, double lo,
                   double hi) {
  double worst = 0;
  for (int i = 0; i <= 200; ++i) {
    const double x = lo + (hi - lo) * i / 200.0;
    worst = std::max(worst, std::abs(fitted(x) - truth(x)));
  }
  return worst;
}

TEST(CalibrateFit, RecoversTheRigsCurvesFromFramesUnderKnownLoads) {
  for (int depth : {8, 16}) {
    SCOPED_TRACE(depth);
    RigSensor sensor(depth, 21);
    const LoadedRun run = loaded_run(sensor, 21);
    // The layout of the sensor as `layout` finds it.
    LayoutInput in;
    in.references = run.references;
    in.frames.push_back(sensor.pressed(0.3));
    in.frames.push_back(sensor.pressed(0.3));
    const Calibration layout = find_layout(in, rig_layout_options()).calibration;
    const std::vector<Sample> samples = measure(layout, run);
    ASSERT_EQ(samples.size(), 21u * 41u);
    for (const Sample& s : samples)
      EXPECT_TRUE(s.contact) << s.where;

    const CurveFit g = fit_normal_curve(samples, {4, 0, 0.02, {}});
    const CurveFit f = fit_shear_curve(samples, {3, 0, 0.02, {}});
    EXPECT_EQ(g.problem, "");
    EXPECT_EQ(f.problem, "");
    const Calibration& t = sensor.truth();
    const double scale = depth == 16 ? 257.0 : 1.0;
    const double g_err = curve_error(g.curve, t.normal_curve, 700 * scale, 13300 * scale);
    const double f_err = curve_error(f.curve, t.shear_curve, 0.0, 0.06);
    std::printf(
        "fit (%d-bit, 861 samples): normal curve within %.4f N of the truth over G 700..13300, "
        "RMS %.4f N, max %.4f N; shear curve within %.4f N over u 0..0.06 mm, RMS %.4f N, max "
        "%.4f N\n",
        depth, g_err, g.all.rms_n, g.all.max_n, f_err, f.all.rms_n, f.all.max_n);
    EXPECT_LT(g_err, 0.04);
    EXPECT_LT(f_err, 0.01);
    EXPECT_LT(g.all.rms_n, 0.02);
    EXPECT_LT(f.all.rms_n, 0.01);
    ASSERT_EQ(g.per_element.size(), 41u);
    for (const ElementError& e : g.per_element) {
      EXPECT_EQ(e.n, 21u);
      EXPECT_LE(e.rms_n, e.max_n);
    }
    EXPECT_EQ(f.per_element.front().n, 42u);  // x and y
    // Monotone through 0: a valid calibration.
    Calibration out = layout;
    out.normal_curve = g.curve;
    out.shear_curve = f.curve;
    EXPECT_NO_THROW(validate(out));
  }
}

std::vector<Sample> clean_samples(int elements, int levels) {
  // Applied F_z = G / 5000 exactly, u = F / 5 exactly.
  std::vector<Sample> out;
  for (int e = 0; e < elements; ++e) {
    for (int l = 1; l <= levels; ++l) {
      Sample s;
      s.element = static_cast<std::uint32_t>(e);
      s.fz_n = 0.2 * l;
      s.G = 1000.0 * l;
      s.has_x = true;
      s.fx_n = 0.05 * (l - levels / 2);
      s.ux_mm = s.fx_n / 5.0;
      s.where = "test:" + std::to_string(out.size() + 2);
      out.push_back(s);
    }
  }
  return out;
}

TEST(CalibrateFit, ExactLinearDataGiveTheLineAndZeroError) {
  const auto samples = clean_samples(3, 8);
  const CurveFit g = fit_normal_curve(samples, {4, 0, 0.02, {}});
  EXPECT_LT(g.all.max_n, 1e-6);
  EXPECT_NEAR(g.curve(4321.0), 4321.0 / 5000.0, 1e-6);
  EXPECT_EQ(g.curve.x().front(), 0.0);
  EXPECT_EQ(g.curve.y().front(), 0.0);
  const CurveFit f = fit_shear_curve(samples, {3, 0, 0.02, {}});
  EXPECT_LT(f.all.max_n, 1e-6);
  EXPECT_NEAR(f.curve.odd(-0.03), -0.15, 1e-6);
}

TEST(CalibrateFit, RefusesNonMonotoneDataTooFewPointsAndALargeError) {
  auto samples = clean_samples(6, 8);
  // Element 4's G falls at its two largest loads.
  for (Sample& s : samples)
    if (s.element == 4 && s.fz_n > 1.3) s.G = 5000.0 - 1000.0 * (s.fz_n - 1.2);
  const std::string mono = refusal([&] { fit_normal_curve(samples, {4, 0, 0.02, {}}); });
  EXPECT_THAT(mono, HasSubstr("normal curve: the data are not monotone: for element 4"));
  EXPECT_THAT(mono, HasSubstr("falls from"));

  // A shear axis flipped for every element.
  samples = clean_samples(6, 8);
  for (Sample& s : samples)
    s.ux_mm = -s.ux_mm;
  const std::string flipped = refusal([&] { fit_shear_curve(samples, {3, 0, 0.02, {}}); });
  EXPECT_THAT(flipped, HasSubstr("shear curve: the data are not monotone"));
  EXPECT_THAT(flipped, HasSubstr("along x"));
  EXPECT_THAT(flipped, HasSubstr("flipped"));

  // Too few points for the knots, and one load only.
  samples = clean_samples(1, 5);
  EXPECT_THAT(refusal([&] {
                fit_normal_curve(samples, {4, 0, 0.02, {}});
              }),
              HasSubstr("normal curve: too few points: 5 samples with a load, at least 8 are "
                        "needed for 4 knots (--normal-knots)"));
  samples = clean_samples(9, 1);
  EXPECT_THAT(refusal([&] {
                fit_normal_curve(samples, {2, 0, 0.02, {}});
              }),
              HasSubstr("at least 2 different loads"));

  // No shear data.
  samples = clean_samples(3, 8);
  for (Sample& s : samples)
    s.has_x = false;
  EXPECT_THAT(refusal([&] {
                fit_shear_curve(samples, {3, 0, 0.02, {}});
              }),
              HasSubstr("--normal-only"));

  // Element 3 is 40 % more sensitive than the others: monotone, but one curve cannot fit it.
  samples = clean_samples(6, 8);
  for (Sample& s : samples)
    if (s.element == 3) s.G *= 1.4;
  const CurveFit bad = fit_normal_curve(samples, {4, 0, 0.02, {}});
  EXPECT_THAT(bad.problem,
              HasSubstr("normal curve: the fit error is too large: element 3 has RMS"));
  EXPECT_THAT(bad.problem, HasSubstr("above the default limit (5 % of the largest load) 0.08 N"));
  const CurveFit loose = fit_normal_curve(samples, {4, 1.0, 0.02, {}});
  EXPECT_EQ(loose.problem, "");
  EXPECT_DOUBLE_EQ(loose.max_rms_n, 1.0);
}

// Shear loads at the noise level: the message names the direction, the loads seen and what to
// record, from the curve the fit replaces (or 10 times the largest load without one).
TEST(CalibrateFit, AnUnobservableDirectionSaysWhatToRecord) {
  auto samples = clean_samples(6, 8);
  util::Random rng(5);
  for (Sample& s : samples) {
    s.fx_n = 0.002 * (static_cast<double>(s.fz_n / 0.2) - 4);  // -0.006 to 0.008 N
    s.ux_mm = 0.004 * rng.normal();                            // the centroid's noise only
  }
  CurveFitOptions o{3, 0, 0.02, {}};
  o.present_curve = PiecewiseLinear({0, 0.02, 0.08}, {0, 0.05, 0.4});
  const std::string msg = refusal([&] { fit_shear_curve(samples, o); });
  std::printf("%s\n", msg.c_str());
  EXPECT_THAT(msg,
              HasSubstr("shear curve: the shear x direction cannot be seen in these samples: "
                        "applied fx_N from -0.006 to 0.008 N moved the measured u along x by"));
  EXPECT_THAT(msg, HasSubstr("record frames with shear x loads of at least"));
  EXPECT_THAT(msg, HasSubstr("N in x, both signs (the present shear curve gives that load"));
  o.present_curve.reset();
  EXPECT_THAT(refusal([&] { fit_shear_curve(samples, o); }),
              HasSubstr("at least 0.08 N in x, both signs (10 times the largest load here)"));

  // Normal loads that all sit below contact: G at the noise level.
  samples = clean_samples(6, 8);
  for (Sample& s : samples)
    s.G = 30 + 10 * rng.normal();
  EXPECT_THAT(refusal([&] {
                fit_normal_curve(samples, {4, 0, 0.02, {}});
              }),
              HasSubstr("normal curve: the normal direction cannot be seen in these samples: "
                        "applied fz_N from 0.2 to 1.6 N"));
}

TEST(CalibrateFit, NonNegativeLeastSquaresMatchesTheKnownSolution) {
  // min |A x - b|, x >= 0, with the unconstrained solution (2, -1): the answer is (x0, 0) with
  // x0 the one-column least squares value.
  const std::vector<double> a = {1, 0, 0, 1, 1, 1};
  const std::vector<double> b = {2, -1, 1};
  const auto x = nnls(a, 2, b);
  EXPECT_NEAR(x[0], 1.5, 1e-9);
  EXPECT_EQ(x[1], 0.0);
  const auto y = nnls(a, 2, {1, 2, 3});
  EXPECT_NEAR(y[0], 1.0, 1e-9);
  EXPECT_NEAR(y[1], 2.0, 1e-9);
}

// --- the CSV files ------------------------------------------------------------------------------

TEST(CalibrateCsv, SamplesRoundTripAndErrorsNameFileLineAndColumn) {
  const std::string text =
      "# a comment\n"
      "element, fz_N, G, fx_N, ux_mm, contact, frame, note\n"
      "3, 0.5, 5000, 0.1, 0.02, 1, \"a,b.pgm\", x\n"
      "\n"
      "4, 0, 12.5, , , 0, b.pgm, y\n";
  const auto s = parse_samples(text, "s.csv");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].element, 3u);
  EXPECT_EQ(s[0].frame, "a,b.pgm");
  EXPECT_TRUE(s[0].has_x);
  EXPECT_FALSE(s[0].has_y);
  EXPECT_FALSE(s[1].has_x);
  EXPECT_FALSE(s[1].contact);
  EXPECT_EQ(s[1].where, "s.csv:5");
  const auto back = parse_samples(format_samples(s), "again");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].fx_n, 0.1);
  EXPECT_EQ(back[0].ux_mm, 0.02);
  EXPECT_EQ(back[0].frame, "a,b.pgm");

  EXPECT_THAT(refusal([] { parse_samples("element,fz_N\n1,2\n", "s.csv"); }),
              HasSubstr("s.csv: the header has no column 'G'"));
  EXPECT_THAT(refusal([] { parse_samples("element,fz_N,G\n1,2,x3\n", "s.csv"); }),
              HasSubstr("s.csv:2: column 'G' must be a finite number, is 'x3'"));
  EXPECT_THAT(refusal([] { parse_samples("element,fz_N,G\n-1,2,3\n", "s.csv"); }),
              HasSubstr("s.csv:2: column 'element' must be an element id"));
  EXPECT_THAT(refusal([] { parse_samples("element,fz_N,G,fx_N\n1,2,3,4\n", "s.csv"); }),
              HasSubstr("columns 'fx_N' and 'ux_mm' go together"));
  EXPECT_THAT(refusal([] { parse_samples("element,fz_N,G\n1,2\n", "s.csv"); }),
              HasSubstr("s.csv:2: 2 fields, the header has 3"));
  EXPECT_THAT(refusal([] { parse_samples("element,fz_N,G\n1,-2,3\n", "s.csv"); }),
              HasSubstr("must not be negative"));

  const auto loads = parse_loads("frame,element,fz_N,fy_N\np/1.pgm,7,0.5,-0.1\n", "l.csv");
  ASSERT_EQ(loads.size(), 1u);
  EXPECT_EQ(loads[0].frame, "p/1.pgm");
  EXPECT_FALSE(loads[0].has_x);
  EXPECT_TRUE(loads[0].has_y);
  EXPECT_EQ(loads[0].fy_n, -0.1);
  EXPECT_THAT(refusal([] { parse_loads("frame,element,fz_N\n", "l.csv"); }),
              HasSubstr("l.csv: no rows after the header"));
}

TEST(CalibrateMeasure, RefusesAnUnknownElementAFrameOfAnotherSizeAndALoadedReference) {
  RigSensor sensor;
  const Calibration& cal = sensor.truth();
  const std::vector<Image> refs = sensor.references(4);
  const std::vector<LoadRow> unknown{{"a.pgm", 99, 0.5, false, 0, false, 0, "l.csv:2"}};
  EXPECT_THAT(refusal([&] {
                measure_samples(cal, refs, unknown, [](const std::string&) { return Image(); }, {});
              }),
              HasSubstr("l.csv:2: element 99 is not in the calibration of 'left'"));
  const std::vector<LoadRow> one{{"a.pgm", 0, 0.5, false, 0, false, 0, "l.csv:2"}};
  EXPECT_THAT(refusal([&] {
                measure_samples(
                    cal, refs, one,
                    [](const std::string&) { return Image(320, 240, PixelFormat::kMono8); }, {});
              }),
              HasSubstr("a.pgm: frame is 320x240 8-bit, the calibration needs 640x480 8-bit"));
  const std::vector<Image> loaded{sensor.pressed(0.5)};
  EXPECT_THAT(refusal([&] {
                measure_samples(cal, loaded, one, [](const std::string&) { return Image(); }, {});
              }),
              HasSubstr("the reference was refused"));
}

}  // namespace
}  // namespace tactile::calibrate
