// The measurement core on small synthetic frames: exact cases, edge cases, contact
// hysteresis, displacement across gaps and the no-load reference.
#include "tactile/extractor.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "synthetic.hpp"

namespace tactile {
namespace {

using testing::SceneOptions;
using testing::Spot;

SceneOptions small_scene(int bit_depth = 8) {
  SceneOptions o;
  o.width = 96;
  o.height = 64;
  o.bit_depth = bit_depth;
  o.noise_sigma = 0;
  o.vignetting = 0.3;
  return o;
}

// A 3 x 2 grid of disks of radius 12 spaced 30 px.
Calibration small_calibration(const SceneOptions& o) {
  return testing::grid_calibration(o, 3, 2, 30.0, 12.0);
}

Image render(const SceneOptions& o, const std::vector<Spot>& spots, std::uint64_t seed = 1) {
  util::Random rng(seed);
  Image img;
  testing::render(o, spots, rng, img);
  return img;
}

Image constant(const SceneOptions& o, std::uint32_t v) {
  Image img(o.width, o.height, o.bit_depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x)
      img.set(x, y, v);
  return img;
}

Extractor with_reference(const Calibration& cal, const Image& ref, ExtractorOptions opt = {}) {
  opt.reference_frames = 1;
  Extractor ex(cal, opt);
  EXPECT_EQ(ex.add_reference_frame(ref.view()).status, ReferenceStatus::kComplete);
  return ex;
}

void expect_all_finite(const Extractor& ex) {
  for (const ElementReading& r : ex.readings()) {
    for (double v : {r.G, r.x_px, r.y_px, r.dx_mm, r.dy_mm, r.ux_mm, r.uy_mm, r.fx, r.fy, r.fz}) {
      EXPECT_TRUE(std::isfinite(v)) << "element " << r.id;
    }
  }
}

class SubPixelSpots : public ::testing::TestWithParam<std::tuple<int, CentroidEstimator>> {};

TEST_P(SubPixelSpots, NoiselessCentroidIsExactToQuantisation) {
  const auto [depth, estimator] = GetParam();
  const SceneOptions o = small_scene(depth);
  const Calibration cal = small_calibration(o);
  ExtractorOptions opt;
  opt.estimator = estimator;
  Extractor ex = with_reference(cal, render(o, {}), opt);

  const double offsets[][2] = {{0.0, 0.0},    {0.25, -0.125}, {0.5, 0.5},
                               {-0.37, 0.81}, {1.3, -2.2},    {-3.05, 2.6}};
  std::vector<Spot> spots;
  for (std::size_t i = 0; i < cal.elements.size(); ++i) {
    Spot s;
    s.center = cal.elements[i].center_px + Vec2{offsets[i][0], offsets[i][1]};
    s.peak = 120;
    s.sigma = 2.0;
    spots.push_back(s);
  }
  ASSERT_EQ(ex.measure(render(o, spots).view(), {0, 0}), MeasureStatus::kOk);
  // Quantisation to 8 bits is the only error: a few thousandths of a pixel (16 bits: far less).
  const double tol = depth == 8 ? 0.02 : 0.003;
  for (std::size_t i = 0; i < spots.size(); ++i) {
    const ElementReading& r = ex.readings()[i];
    ASSERT_TRUE(r.contact) << "element " << i;
    EXPECT_NEAR(r.x_px, spots[i].center.x, tol) << "element " << i;
    EXPECT_NEAR(r.y_px, spots[i].center.y, tol) << "element " << i;
  }
  expect_all_finite(ex);
}

INSTANTIATE_TEST_SUITE_P(
    DepthsAndEstimators, SubPixelSpots,
    ::testing::Combine(::testing::Values(8, 16),
                       ::testing::Values(CentroidEstimator::kPlain, CentroidEstimator::kThresholded,
                                         CentroidEstimator::kWindowed, CentroidEstimator::kGaussian,
                                         CentroidEstimator::kGaussianAxes)));

TEST(Extractor, AllZeroFramesGiveNoContactAndFiniteValues) {
  const SceneOptions o = small_scene();
  Extractor ex = with_reference(small_calibration(o), constant(o, 0));
  ASSERT_EQ(ex.measure(constant(o, 0).view(), {0, 0}), MeasureStatus::kOk);
  for (const ElementReading& r : ex.readings()) {
    EXPECT_FALSE(r.contact);
    EXPECT_EQ(r.G, 0.0);
    EXPECT_EQ(r.fz, 0.0);
  }
  expect_all_finite(ex);
}

TEST(Extractor, SaturatedFramePutsEveryCentroidAtItsDiskCentre) {
  for (int depth : {8, 16}) {
    const SceneOptions o = small_scene(depth);
    const Calibration cal = small_calibration(o);
    Extractor ex = with_reference(cal, render(o, {}));
    ASSERT_EQ(ex.measure(constant(o, depth == 8 ? 255 : 65535).view(), {0, 0}), MeasureStatus::kOk);
    for (std::size_t i = 0; i < cal.elements.size(); ++i) {
      const ElementReading& r = ex.readings()[i];
      ASSERT_TRUE(r.contact);
      // The background falls off with vignetting, so the increment is not quite flat: the
      // centroid stays within a fraction of a pixel of the disk centre.
      EXPECT_NEAR(r.x_px, cal.elements[i].center_px.x, 0.3);
      EXPECT_NEAR(r.y_px, cal.elements[i].center_px.y, 0.3);
      EXPECT_GT(r.fz, 0.0);
    }
    expect_all_finite(ex);
  }
}

TEST(Extractor, OneBrightPixelIsItsOwnCentroid) {
  const SceneOptions o = small_scene();
  Calibration cal = small_calibration(o);
  cal.contact_on = 100;
  cal.contact_off = 50;
  for (CentroidEstimator est :
       {CentroidEstimator::kPlain, CentroidEstimator::kThresholded, CentroidEstimator::kWindowed,
        CentroidEstimator::kGaussian, CentroidEstimator::kGaussianAxes}) {
    ExtractorOptions opt;
    opt.estimator = est;
    Extractor ex = with_reference(cal, constant(o, 20), opt);
    Image frame = constant(o, 20);
    const int px = static_cast<int>(cal.elements[4].center_px.x) + 3;
    const int py = static_cast<int>(cal.elements[4].center_px.y) - 2;
    frame.set(px, py, 255);
    ASSERT_EQ(ex.measure(frame.view(), {0, 0}), MeasureStatus::kOk);
    const ElementReading& r = ex.readings()[4];
    ASSERT_TRUE(r.contact);
    EXPECT_DOUBLE_EQ(r.G, 255 - 20 - cal.noise_floor);
    EXPECT_DOUBLE_EQ(r.x_px, px);
    EXPECT_DOUBLE_EQ(r.y_px, py);
    for (std::size_t i = 0; i < cal.elements.size(); ++i) {
      if (i != 4) {
        EXPECT_FALSE(ex.readings()[i].contact);
      }
    }
  }
}

TEST(Extractor, NegativeIncrementsWeighNothing) {
  const SceneOptions o = small_scene();
  Extractor ex = with_reference(small_calibration(o), constant(o, 200));
  ASSERT_EQ(ex.measure(constant(o, 10).view(), {0, 0}), MeasureStatus::kOk);
  for (const ElementReading& r : ex.readings()) {
    EXPECT_FALSE(r.contact);
    EXPECT_EQ(r.G, 0.0);
  }
  expect_all_finite(ex);
}

TEST(Extractor, DiskTouchingTheImageBorderIsMeasured) {
  SceneOptions o = small_scene();
  Calibration cal = small_calibration(o);
  // Disk reaching the pixel area's corner exactly: x in [-0.5, ...], y in [-0.5, ...].
  cal.elements.resize(1);
  cal.elements[0].center_px = {9.5, 9.5};
  cal.elements[0].radius_px = 10.0;
  cal.elements[0].zero_px = cal.elements[0].center_px;
  ASSERT_NO_THROW(validate(cal));
  Extractor ex = with_reference(cal, render(o, {}));
  Spot s;
  s.center = {8.3, 10.6};
  s.sigma = 1.8;
  ASSERT_EQ(ex.measure(render(o, {s}).view(), {0, 0}), MeasureStatus::kOk);
  ASSERT_TRUE(ex.readings()[0].contact);
  EXPECT_NEAR(ex.readings()[0].x_px, 8.3, 0.01);
  EXPECT_NEAR(ex.readings()[0].y_px, 10.6, 0.01);
}

TEST(Extractor, OnePixelDiskMeasuresThatPixel) {
  const SceneOptions o = small_scene();
  Calibration cal = small_calibration(o);
  cal.elements.resize(1);
  cal.elements[0].center_px = {40, 30};
  cal.elements[0].radius_px = 0;
  cal.elements[0].zero_px = {40, 30};
  cal.contact_on = 10;
  cal.contact_off = 5;
  Extractor ex = with_reference(cal, constant(o, 30));
  Image frame = constant(o, 30);
  frame.set(40, 30, 90);
  frame.set(41, 30, 250);  // outside S: ignored
  ASSERT_EQ(ex.measure(frame.view(), {0, 0}), MeasureStatus::kOk);
  const ElementReading& r = ex.readings()[0];
  ASSERT_TRUE(r.contact);
  EXPECT_DOUBLE_EQ(r.G, 90 - 30 - cal.noise_floor);
  EXPECT_DOUBLE_EQ(r.x_px, 40);
  EXPECT_DOUBLE_EQ(r.y_px, 30);
}

TEST(Extractor, NoFramesNoReferenceNoMeasurement) {
  const SceneOptions o = small_scene();
  Extractor ex(small_calibration(o));
  EXPECT_FALSE(ex.has_reference());
  EXPECT_EQ(ex.measure(constant(o, 0).view(), {0, 0}), MeasureStatus::kNoReference);
  EXPECT_EQ(ex.finish_reference().status, ReferenceStatus::kNoFrames);
  EXPECT_FALSE(ex.has_reference());
  for (const ElementReading& r : ex.readings())
    EXPECT_FALSE(r.contact);
}

TEST(Extractor, WrongSizeOrDepthIsReportedNotMeasured) {
  const SceneOptions o = small_scene();
  Extractor ex = with_reference(small_calibration(o), render(o, {}));
  SceneOptions other = o;
  other.width = 95;
  EXPECT_EQ(ex.measure(render(other, {}).view(), {0, 0}), MeasureStatus::kWrongSize);
  EXPECT_EQ(ex.measure(render(small_scene(16), {}).view(), {0, 0}), MeasureStatus::kWrongFormat);
  EXPECT_EQ(ex.measure(ImageView{}, {0, 0}), MeasureStatus::kWrongSize);
}

TEST(Extractor, ContactHasHysteresis) {
  const SceneOptions o = small_scene();
  Calibration cal = small_calibration(o);
  Extractor ex = with_reference(cal, constant(o, 10));
  // A flat patch inside element 0 whose G we set exactly: n pixels of increment d.
  const auto frame_with_g = [&](double g) {
    Image f = constant(o, 10);
    const Vec2 c = cal.elements[0].center_px;
    const int per_pixel = 100;  // increment 100 -> weight 96
    int n = static_cast<int>(std::round(g / (per_pixel - cal.noise_floor)));
    for (int dy = -3; dy <= 3 && n > 0; ++dy)
      for (int dx = -3; dx <= 3 && n > 0; ++dx, --n)
        f.set(static_cast<int>(c.x) + dx, static_cast<int>(c.y) + dy, 10 + per_pixel);
    return f;
  };
  struct Step {
    double g;
    bool contact;
  };
  // on = 400, off = 250: 288 stays off from below, 480 enters, 288 stays on, 192 leaves.
  const Step steps[] = {{0, false},  {288, false}, {480, true},  {384, true},
                        {288, true}, {192, false}, {384, false}, {480, true}};
  std::uint64_t seq = 0;
  for (const Step& s : steps) {
    ASSERT_EQ(ex.measure(frame_with_g(s.g).view(), {seq++, 0}), MeasureStatus::kOk);
    EXPECT_EQ(ex.readings()[0].contact, s.contact) << "G " << ex.readings()[0].G;
    if (!s.contact) {
      EXPECT_EQ(ex.readings()[0].x_px, 0.0);
      EXPECT_EQ(ex.readings()[0].fz, 0.0);
      EXPECT_EQ(ex.readings()[0].dx_mm, 0.0);
    }
  }
}

TEST(Extractor, DisplacementNeedsContactInBothFramesAndScalesAcrossGaps) {
  const SceneOptions o = small_scene();
  const Calibration cal = small_calibration(o);
  ExtractorOptions opt;
  opt.max_gap_frames = 4;
  Extractor ex = with_reference(cal, render(o, {}), opt);
  const Vec2 c = cal.elements[0].center_px;
  const auto spot_at = [&](double dx) {
    Spot s;
    s.center = c + Vec2{dx, 0};
    s.peak = 150;
    s.sigma = 2.0;
    return render(o, {s});
  };
  const double mm = cal.mm_per_px;

  ASSERT_EQ(ex.measure(spot_at(0).view(), {10, 0}), MeasureStatus::kOk);
  EXPECT_FALSE(ex.readings()[0].has_displacement);  // first frame: no predecessor
  EXPECT_EQ(ex.readings()[0].dx_mm, 0.0);

  ASSERT_EQ(ex.measure(spot_at(0.5).view(), {11, 0}), MeasureStatus::kOk);
  EXPECT_TRUE(ex.readings()[0].has_displacement);
  EXPECT_NEAR(ex.readings()[0].dx_mm, 0.5 * mm, 0.01 * mm);

  // Two frames lost (sequence 12 and 13): 1.5 px over 3 periods is 0.5 px per period.
  ASSERT_EQ(ex.measure(spot_at(2.0).view(), {14, 0}), MeasureStatus::kOk);
  EXPECT_NEAR(ex.readings()[0].dx_mm, 0.5 * mm, 0.01 * mm);

  // A gap longer than max_gap_frames forgets the previous frame.
  ASSERT_EQ(ex.measure(spot_at(3.0).view(), {19, 0}), MeasureStatus::kOk);
  EXPECT_FALSE(ex.readings()[0].has_displacement);
  EXPECT_EQ(ex.readings()[0].dx_mm, 0.0);

  // Duplicated and reversed sequence numbers never produce a displacement.
  ASSERT_EQ(ex.measure(spot_at(3.5).view(), {19, 0}), MeasureStatus::kOk);
  EXPECT_EQ(ex.readings()[0].dx_mm, 0.0);
  ASSERT_EQ(ex.measure(spot_at(4.0).view(), {18, 0}), MeasureStatus::kOk);
  EXPECT_EQ(ex.readings()[0].dx_mm, 0.0);

  // Leaving contact and coming back: no displacement on the first frame back.
  ASSERT_EQ(ex.measure(render(o, {}).view(), {19, 0}), MeasureStatus::kOk);
  EXPECT_FALSE(ex.readings()[0].contact);
  ASSERT_EQ(ex.measure(spot_at(1.0).view(), {20, 0}), MeasureStatus::kOk);
  EXPECT_TRUE(ex.readings()[0].contact);
  EXPECT_FALSE(ex.readings()[0].has_displacement);
  EXPECT_EQ(ex.readings()[0].dx_mm, 0.0);

  // forget_previous(): the next frame has no predecessor.
  ex.forget_previous();
  ASSERT_EQ(ex.measure(spot_at(1.5).view(), {21, 0}), MeasureStatus::kOk);
  EXPECT_FALSE(ex.readings()[0].has_displacement);
}

TEST(Extractor, ForcesFollowTheCalibrationCurves) {
  const SceneOptions o = small_scene();
  Calibration cal = small_calibration(o);
  for (auto& e : cal.elements)
    e.zero_px = e.center_px + Vec2{0.4, -0.3};
  Extractor ex = with_reference(cal, render(o, {}));
  std::vector<Spot> spots;
  for (std::size_t i = 0; i < cal.elements.size(); ++i) {
    Spot s;
    s.center = cal.elements[i].center_px +
               Vec2{0.8 * static_cast<double>(i) - 2, 1.1 - 0.5 * static_cast<double>(i)};
    s.peak = 70.0 + 30.0 * static_cast<double>(i);
    s.sigma = 1.5 + 0.3 * static_cast<double>(i);
    spots.push_back(s);
  }
  ASSERT_EQ(ex.measure(render(o, spots).view(), {0, 0}), MeasureStatus::kOk);
  for (std::size_t i = 0; i < spots.size(); ++i) {
    const ElementReading& r = ex.readings()[i];
    ASSERT_TRUE(r.contact);
    EXPECT_DOUBLE_EQ(r.fz, cal.normal_curve(r.G));
    EXPECT_DOUBLE_EQ(r.ux_mm, (r.x_px - cal.elements[i].zero_px.x) * cal.mm_per_px);
    EXPECT_DOUBLE_EQ(r.uy_mm, (r.y_px - cal.elements[i].zero_px.y) * cal.mm_per_px);
    EXPECT_DOUBLE_EQ(r.fx, cal.shear_curve.odd(r.ux_mm));
    EXPECT_DOUBLE_EQ(r.fy, cal.shear_curve.odd(r.uy_mm));
    // G is the volume of the spot above the noise floor: close to 2 pi sigma^2 peak.
    const double volume = 2 * M_PI * spots[i].sigma * spots[i].sigma * spots[i].peak;
    EXPECT_NEAR(r.G, volume, 0.25 * volume);
    EXPECT_LT(r.G, volume);
  }
}

// --- reference -------------------------------------------------------------------------------

TEST(Reference, IsTheMeanOfItsFrames) {
  const SceneOptions o = small_scene();
  ExtractorOptions opt;
  opt.reference_frames = 4;
  Extractor ex(small_calibration(o), opt);
  for (std::uint32_t v : {10U, 11U, 11U, 12U}) {
    const auto r = ex.add_reference_frame(constant(o, v).view());
    EXPECT_EQ(r.status, v == 12U ? ReferenceStatus::kComplete : ReferenceStatus::kCollecting);
  }
  ASSERT_TRUE(ex.has_reference());
  EXPECT_EQ(ex.reference_image().get(5, 5), 11U);
  // Mean 11.0: a frame of 11 + floor + 1 weighs exactly 1 per pixel in every disk.
  Image f = constant(o, 11 + 4 + 1);
  ASSERT_EQ(ex.measure(f.view(), {0, 0}), MeasureStatus::kOk);
  EXPECT_DOUBLE_EQ(ex.readings()[0].G,
                   static_cast<double>(disk_pixel_count(ex.calibration().elements[0].center_px,
                                                        ex.calibration().elements[0].radius_px)));
}

TEST(Reference, KeepsSubGrayLevelPrecision) {
  const SceneOptions o = small_scene();
  ExtractorOptions opt;
  opt.reference_frames = 2;
  Calibration cal = small_calibration(o);
  cal.noise_floor = 0;
  cal.contact_on = 1e6;  // half a gray level everywhere is no touch
  cal.contact_off = 1e5;
  Extractor ex(cal, opt);
  ex.add_reference_frame(constant(o, 10).view());
  ASSERT_EQ(ex.add_reference_frame(constant(o, 11).view()).status, ReferenceStatus::kComplete);
  ASSERT_EQ(ex.measure(constant(o, 11).view(), {0, 0}), MeasureStatus::kOk);
  const double n =
      static_cast<double>(disk_pixel_count(cal.elements[0].center_px, cal.elements[0].radius_px));
  EXPECT_DOUBLE_EQ(ex.readings()[0].G, 0.5 * n);
}

TEST(Reference, RefusesAFrameThatMovesDuringCapture) {
  const SceneOptions o = small_scene();
  const Calibration cal = small_calibration(o);
  ExtractorOptions opt;
  opt.reference_frames = 4;
  Extractor ex(cal, opt);
  EXPECT_EQ(ex.add_reference_frame(render(o, {}, 1).view()).status, ReferenceStatus::kCollecting);
  Spot s;
  s.center = cal.elements[2].center_px;
  s.peak = 100;
  const auto r = ex.add_reference_frame(render(o, {s}, 2).view());
  EXPECT_EQ(r.status, ReferenceStatus::kRefusedMotion);
  EXPECT_EQ(r.element_id, cal.elements[2].id);
  EXPECT_GE(r.value, cal.contact_on);
  EXPECT_FALSE(ex.has_reference());
}

TEST(Reference, RefusesALoadAgainstThePreviousReference) {
  const SceneOptions o = small_scene();
  const Calibration cal = small_calibration(o);
  ExtractorOptions opt;
  opt.reference_frames = 2;
  opt.reference_spot_check = false;  // only the comparison with the previous reference
  Extractor ex(cal, opt);
  ex.add_reference_frame(render(o, {}, 1).view());
  ASSERT_EQ(ex.add_reference_frame(render(o, {}, 2).view()).status, ReferenceStatus::kComplete);
  Spot s;
  s.center = cal.elements[5].center_px;
  s.peak = 60;
  ex.begin_reference();
  ex.add_reference_frame(render(o, {s}, 3).view());
  const auto r = ex.add_reference_frame(render(o, {s}, 4).view());
  EXPECT_EQ(r.status, ReferenceStatus::kRefusedLoad);
  EXPECT_EQ(r.element_id, cal.elements[5].id);
  // The old reference stays in use.
  ASSERT_TRUE(ex.has_reference());
  ASSERT_EQ(ex.measure(render(o, {s}, 5).view(), {0, 0}), MeasureStatus::kOk);
  EXPECT_TRUE(ex.readings()[5].contact);
  // An unloaded capture replaces it.
  ex.begin_reference();
  ex.add_reference_frame(render(o, {}, 6).view());
  EXPECT_EQ(ex.add_reference_frame(render(o, {}, 7).view()).status, ReferenceStatus::kComplete);
}

TEST(Reference, RefusesASpotWithoutAPreviousReference) {
  SceneOptions o = small_scene();
  o.noise_sigma = 2;
  const Calibration cal = small_calibration(o);
  ExtractorOptions opt;
  opt.reference_frames = 3;
  Extractor ex(cal, opt);
  Spot s;
  s.center = cal.elements[1].center_px + Vec2{1, -1};
  s.peak = 50;
  ex.add_reference_frame(render(o, {s}, 1).view());
  ex.add_reference_frame(render(o, {s}, 2).view());
  const auto r = ex.add_reference_frame(render(o, {s}, 3).view());
  EXPECT_EQ(r.status, ReferenceStatus::kRefusedSpot);
  EXPECT_EQ(r.element_id, cal.elements[1].id);
  EXPECT_FALSE(ex.has_reference());
  // The vignetted, noisy background alone passes.
  for (std::uint64_t seed : {4, 5, 6})
    ex.add_reference_frame(render(o, {}, seed).view());
  EXPECT_TRUE(ex.has_reference());
}

TEST(Reference, RefusesWrongGeometry) {
  const SceneOptions o = small_scene();
  Extractor ex(small_calibration(o));
  EXPECT_EQ(ex.add_reference_frame(render(small_scene(16), {}).view()).status,
            ReferenceStatus::kWrongFormat);
  SceneOptions other = o;
  other.height = 10;
  EXPECT_EQ(ex.add_reference_frame(render(other, {}).view()).status, ReferenceStatus::kWrongSize);
}

TEST(Extractor, RefusesBadOptionsAtConstruction) {
  const Calibration cal = small_calibration(small_scene());
  ExtractorOptions opt;
  opt.reference_frames = 0;
  EXPECT_THROW(Extractor(cal, opt), std::invalid_argument);
  opt = {};
  opt.max_gap_frames = 0;
  EXPECT_THROW(Extractor(cal, opt), std::invalid_argument);
  Calibration bad = cal;
  bad.elements.clear();
  EXPECT_THROW(Extractor{bad}, CalibrationError);
}

}  // namespace
}  // namespace tactile
