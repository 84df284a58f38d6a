// Optics (docs/rig.md): the rig's calibration, rendering through the inverse curves measured
// back by the real extractor, honest noise statistics, redrawing only what changed.
#include "tactile/rig/optics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "tactile/config/calibration_file.hpp"
#include "tactile/extractor.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {
namespace {

Calibration calibration(const CameraParams& cam, const SensorOpticsParams& opt = {}) {
  World w{WorldParams{}};
  const auto normals = w.element_normals();
  return make_calibration("left", cam, opt, normals);
}

SensorOpticsParams feelers() {
  SensorOpticsParams o;
  o.element_model = ElementModel::kFeelers;
  return o;
}

// A camera without noise: the image is the rounded noiseless one.
CameraParams noiseless_camera() {
  CameraParams cam;
  cam.noise_sigma = 0.0;
  return cam;
}

TEST(Optics, CalibrationHas41ElementsOnRingsAndRoundTrips) {
  CameraParams cam;
  const Calibration cal = calibration(cam);
  ASSERT_EQ(cal.elements.size(), 41U);
  EXPECT_NEAR(cal.elements[0].center_px.x, 319.5, 1e-9);
  EXPECT_NEAR(cal.elements[0].normal.z, 1.0, 1e-12);
  for (const ElementCalibration& e : cal.elements)
    EXPECT_NEAR(norm(e.normal), 1.0, 1e-12);
  // Ring 3 sits 180 px from the centre.
  EXPECT_NEAR(norm(cal.elements[40].center_px - cal.elements[0].center_px), 180.0, 1e-9);
  const Calibration back = config::parse_calibration(config::format_calibration(cal), "rt");
  EXPECT_EQ(back.elements.size(), 41U);
  EXPECT_EQ(back.normal_curve.x().back(), cal.normal_curve.x().back());
}

struct MeasureCase {
  int bit_depth;
  ElementModel model;
};

// Both element models: the measured G follows the calibration's curve alike. The Gaussian spot's
// centroid is its deflection; the feeler cluster's is not (FeelerCentroid).
// The extractor's no-load reference from 16 frames of the renderer.
bool take_reference(Renderer& r, util::Random& rng, Extractor& ex) {
  const std::vector<ElementLoad> none(41);
  Image img;
  ex.begin_reference();
  for (int k = 0; k < 16; ++k) {
    r.render(none, rng, img);
    ex.add_reference_frame(img.view());
  }
  return ex.has_reference();
}

class RenderMeasure : public ::testing::TestWithParam<MeasureCase> {};

TEST_P(RenderMeasure, ExtractorMeasuresWhatWasRendered) {
  CameraParams cam;
  cam.bit_depth = GetParam().bit_depth;
  SensorOpticsParams opt;
  opt.element_model = GetParam().model;
  const Calibration cal = calibration(cam, opt);
  Renderer r(cal, cam, opt, 11);
  Extractor ex(cal);
  util::Random rng(3);
  Image img;
  std::vector<ElementLoad> loads(41);
  ASSERT_TRUE(take_reference(r, rng, ex));
  const std::vector<double> forces{0.1, 0.3, 0.8, 1.5, 2.5};
  double sq = 0;
  int n = 0;
  for (int frame = 0; frame < 20; ++frame) {
    for (std::size_t k = 0; k < loads.size(); ++k) {
      const auto kd = static_cast<double>(k);
      loads[k] = {forces[k % forces.size()], 0.01 * std::sin(kd + frame * 0.1),
                  -0.02 * std::cos(kd * 0.7)};
    }
    r.render(loads, rng, img);
    ASSERT_EQ(ex.measure(img.view(), {static_cast<std::uint64_t>(frame + 1), 0}),
              MeasureStatus::kOk);
    for (std::size_t k = 0; k < loads.size(); ++k) {
      const ElementReading& m = ex.readings()[k];
      ASSERT_TRUE(m.contact) << k;
      sq += (m.fz - loads[k].fz_n) * (m.fz - loads[k].fz_n);
      ++n;
      if (opt.element_model != ElementModel::kGaussian) continue;
      EXPECT_NEAR(m.ux_mm, loads[k].ux_mm, 0.0015) << k;
      EXPECT_NEAR(m.uy_mm, loads[k].uy_mm, 0.0015) << k;
    }
  }
  // Normal force within 1 % of the curve's full scale (3 N), RMS.
  EXPECT_LT(std::sqrt(sq / n), 0.03);
}

INSTANTIATE_TEST_SUITE_P(BitDepthsAndModels, RenderMeasure,
                         ::testing::Values(MeasureCase{8, ElementModel::kGaussian},
                                           MeasureCase{16, ElementModel::kGaussian},
                                           MeasureCase{8, ElementModel::kFeelers},
                                           MeasureCase{16, ElementModel::kFeelers}));

// Read noise alone (every pixel the same sigma) and with shot noise (each pixel's sigma from its
// value): the renderer takes a different path for each.
TEST(Optics, NoiseHasTheStatedStatistics) {
  for (const double gain : {0.0, 10.0}) {
    SCOPED_TRACE(gain);
    CameraParams cam;
    cam.noise_sigma = 3.0;
    cam.shot_noise_gain = gain;
    const Calibration cal = calibration(cam);
    Renderer r(cal, cam, SensorOpticsParams{}, 5);
    util::Random rng(9);
    Image img;
    std::vector<ElementLoad> loads(41);
    // Pixels of the centre element's disk, over many frames: mean, sigma, frame-to-frame
    // correlation.
    const int frames = 400;
    const Vec2 c = cal.elements[0].center_px;
    std::vector<int> xs;
    std::vector<int> ys;
    for (int dy = -8; dy <= 8; dy += 2)
      for (int dx = -8; dx <= 8; dx += 2) {
        xs.push_back(static_cast<int>(c.x) + dx);
        ys.push_back(static_cast<int>(c.y) + dy);
      }
    std::vector<double> sum(xs.size()), sum2(xs.size()), lag(xs.size()), prev(xs.size());
    for (int f = 0; f < frames; ++f) {
      r.render(loads, rng, img);
      for (std::size_t i = 0; i < xs.size(); ++i) {
        const double v = img.get(xs[i], ys[i]) - r.background_at(xs[i], ys[i]);
        sum[i] += v;
        sum2[i] += v * v;
        if (f > 0) lag[i] += v * prev[i];
        prev[i] = v;
      }
    }
    double mean = 0, var = 0, corr = 0, expected_var = 0;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      mean += sum[i] / frames;
      var += sum2[i] / frames;
      corr += lag[i] / (frames - 1);
      // Shot noise: variance value / gain (8-bit levels). Rounding adds 1/12.
      const double shot = gain > 0 ? r.background_at(xs[i], ys[i]) / gain : 0.0;
      expected_var += 9.0 + shot + 1.0 / 12;
    }
    const auto n = static_cast<double>(xs.size());
    mean /= n;
    var /= n;
    corr /= n;
    expected_var /= n;
    EXPECT_NEAR(mean, 0.0, 0.1);
    EXPECT_NEAR(std::sqrt(var), std::sqrt(expected_var), 0.1);
    if (gain > 0) {
      EXPECT_GT(expected_var, 9.0 + 1.0 / 12 + 2.0);  // the shot noise shows
    }
    EXPECT_NEAR(corr / var, 0.0, 0.05);
  }
}

// The cameras' background outside the disks lives as a camera's does (fresh noise every frame,
// the vignetted level), and the disks' pixels (all the measurement reads) are the same with it
// and without it, so it moves no measured figure.
TEST(Optics, LiveBackgroundOutsideTheDisksLeavesTheDisksAlone) {
  for (int depth : {8, 16}) {
    SCOPED_TRACE(depth);
    CameraParams live;
    live.bit_depth = depth;
    CameraParams frozen = live;
    frozen.live_background = false;
    const Calibration cal = calibration(live);
    const double scale = depth == 16 ? 257.0 : 1.0;
    Renderer rl(cal, live, SensorOpticsParams{}, 5);
    Renderer rf(cal, frozen, SensorOpticsParams{}, 5);
    util::Random rng_l(9);
    util::Random rng_f(9);
    std::vector<ElementLoad> loads(41, ElementLoad{0.4, 0.01, -0.01});
    // The disks S: the pixels each frame's spots and noise are drawn into.
    std::vector<bool> in_disk(static_cast<std::size_t>(cal.width * cal.height), false);
    for (const ElementCalibration& e : cal.elements)
      for (const DiskRow& row : disk_rows(e.center_px, e.radius_px))
        for (int x = row.x0; x < row.x1; ++x)
          in_disk[static_cast<std::size_t>(row.y * cal.width + x)] = true;
    Image l0;
    Image l1;
    Image f1;
    rl.render(loads, rng_l, l0);
    Image f0;
    rf.render(loads, rng_f, f0);
    l1 = l0;
    rl.render(loads, rng_l, l1);
    f1 = f0;
    rf.render(loads, rng_f, f1);
    double s = 0;
    double s2 = 0;
    double level = 0;
    int n = 0;
    int zero = 0;
    int frozen_changed = 0;
    for (int y = 0; y < cal.height; ++y) {
      for (int x = 0; x < cal.width; ++x) {
        if (in_disk[static_cast<std::size_t>(y * cal.width + x)]) {
          ASSERT_EQ(l1.view().at(x, y), f1.view().at(x, y)) << x << "," << y;
          continue;
        }
        const double d = (static_cast<double>(l1.view().at(x, y)) - l0.view().at(x, y)) / scale;
        s += d;
        s2 += d * d;
        zero += d == 0 ? 1 : 0;
        level += static_cast<double>(l1.view().at(x, y)) / scale;
        ++n;
        // Without the live background nothing outside the disks changes.
        frozen_changed += f1.view().at(x, y) != f0.view().at(x, y) ? 1 : 0;
      }
    }
    EXPECT_EQ(frozen_changed, 0);
    const double sd = std::sqrt(s2 / n - (s / n) * (s / n));
    // Two frames' difference: sqrt(2) x the read noise of 2 (rounding adds 1/12 per frame for
    // 8-bit; a pixel repeats its bank row 1 time in 16).
    EXPECT_NEAR(sd, std::sqrt(2.0 * (4.0 + (depth == 8 ? 1.0 / 12 : 0.0)) * 15.0 / 16.0), 0.1);
    EXPECT_LT(static_cast<double>(zero) / n, 0.25);
    EXPECT_NEAR(level / n, rl.background_at(319.5, 239.5) * (1 - 0.35 * 0.4) / scale, 3.0);
  }
}

// The renderer draws only the disks' pixels, each spot from one exp per row and one per column:
// without noise every disk pixel is the direct form's, round(bg + peak exp(-r^2 / 2 sigma^2))
// with the exp of each pixel's own offsets, bit for bit; the rest of each disk's bounding box
// keeps the background of the first frame.
TEST(Optics, DiskPixelsAreTheDirectFormsBitForBit) {
  struct Case {
    double fz_n, ux_mm, uy_mm;
  };
  const std::vector<Case> cases{{0, 0, 0},         {0.05, 0, 0},      {0.4, 0.01, -0.01},
                                {1.5, -0.2, 0.15}, {3.0, 0.33, 0.33}, {0.8, 0.5, -0.45},
                                {6.0, -0.05, 0.0}, {0.2, 0.0, 0.6}};
  for (int depth : {8, 16}) {
    SCOPED_TRACE(depth);
    CameraParams cam;
    cam.bit_depth = depth;
    cam.noise_sigma = 0;
    cam.live_background = false;
    const SensorOpticsParams opt;
    const Calibration cal = calibration(cam);
    Renderer r(cal, cam, opt, 5);
    util::Random rng(3);
    Image img;
    std::vector<ElementLoad> loads(41);
    r.render(loads, rng, img);
    const Image first = img;
    for (std::size_t k = 0; k < loads.size(); ++k) {
      const Case& c = cases[k % cases.size()];
      loads[k] = {c.fz_n, c.ux_mm, c.uy_mm};
    }
    r.render(loads, rng, img);
    const double scale = depth == 16 ? 257.0 : 1.0;
    const double top = depth == 16 ? 65535.0 : 255.0;
    std::vector<bool> in_disk(static_cast<std::size_t>(cal.width * cal.height), false);
    int spot_pixels = 0;
    for (std::size_t k = 0; k < loads.size(); ++k) {
      const ElementCalibration& e = cal.elements[k];
      const double p =
          loads[k].fz_n > 0 ? r.strength_for_g(k, cal.normal_curve.inverse(loads[k].fz_n)) : 0.0;
      const double sigma =
          std::clamp(std::sqrt(p / (2.0 * std::numbers::pi * opt.spot_peak_ref * scale)),
                     opt.spot_sigma_min_px, opt.spot_sigma_max_px);
      const double peak = p / (2.0 * std::numbers::pi * sigma * sigma);
      const double cx = e.zero_px.x + loads[k].ux_mm / cal.mm_per_px;
      const double cy = e.zero_px.y + loads[k].uy_mm / cal.mm_per_px;
      const double inv = 1.0 / (2.0 * sigma * sigma);
      for (const DiskRow& row : disk_rows(e.center_px, e.radius_px)) {
        const int y = row.y;
        const double ey = peak > 0 ? peak * std::exp(-(y - cy) * (y - cy) * inv) : 0.0;
        for (int x = row.x0; x < row.x1; ++x) {
          in_disk[static_cast<std::size_t>(y * cal.width + x)] = true;
          const auto bg = static_cast<float>(r.background_at(x, y));
          const double spot = ey > 1e-6 ? ey * std::exp(-(x - cx) * (x - cx) * inv) : 0.0;
          const auto v = static_cast<float>(static_cast<double>(bg) + spot);
          const float clamped = std::clamp(v, 0.0F, static_cast<float>(top));
          const auto expected = static_cast<std::uint32_t>(clamped + 0.5F);
          ASSERT_EQ(img.view().at(x, y), expected) << "element " << k << " at " << x << "," << y;
          spot_pixels += spot > 0.5 ? 1 : 0;
        }
      }
    }
    EXPECT_GT(spot_pixels, 500);  // the cases draw visible spots, not only background
    for (int y = 0; y < cal.height; ++y) {
      for (int x = 0; x < cal.width; ++x) {
        if (!in_disk[static_cast<std::size_t>(y * cal.width + x)]) {
          ASSERT_EQ(img.view().at(x, y), first.view().at(x, y)) << x << "," << y;
        }
      }
    }
  }
}

TEST(Optics, OnlyChangedSpotsAreRedrawn) {
  CameraParams cam;
  const Calibration cal = calibration(cam);
  Renderer r(cal, cam, SensorOpticsParams{}, 5);
  util::Random rng(1);
  Image img;
  std::vector<ElementLoad> loads(41);
  r.render(loads, rng, img);
  EXPECT_EQ(r.redrawn_spots(), 41U);
  r.render(loads, rng, img);
  EXPECT_EQ(r.redrawn_spots(), 0U);
  loads[3].fz_n = 0.4;
  loads[7].uy_mm = 0.01;
  r.render(loads, rng, img);
  EXPECT_EQ(r.redrawn_spots(), 2U);
}

TEST(Optics, ExpectedGInvertsToTheStrength) {
  CameraParams cam;
  const Calibration cal = calibration(cam);
  Renderer r(cal, cam, SensorOpticsParams{}, 5);
  for (double p : {500.0, 3000.0, 12000.0, 30000.0}) {
    EXPECT_NEAR(r.strength_for_g(5, r.expected_g(5, p)), p, 1e-6 * p + 1e-3);
  }
  EXPECT_EQ(r.strength_for_g(5, 0.0), 0.0);
}

// The paper's own estimator (eq. 3-4, no floor) on a noiseless camera measures the truth's
// centroid, up to the pixels' rounding. (The default Gaussian-weighted estimator is unbiased only
// on symmetric spots; on a sheared cluster it is not: issue 38, item 3.)
TEST(FeelerCentroid, ThePapersCentroidOnANoiselessImageIsTheTruths) {
  const CameraParams cam = noiseless_camera();
  const SensorOpticsParams opt = feelers();
  const Calibration cal = calibration(cam, opt);
  Renderer r(cal, cam, opt, 11);
  ExtractorOptions eo;
  eo.estimator = CentroidEstimator::kPlain;
  Extractor ex(cal, eo);
  util::Random rng(3);
  Image img;
  std::vector<ElementLoad> loads(41);
  ASSERT_TRUE(take_reference(r, rng, ex));
  for (std::size_t k = 0; k < loads.size(); ++k) {
    const auto kd = static_cast<double>(k);
    loads[k] = {0.2 + 0.05 * kd, 0.03 * std::sin(kd), -0.03 * std::cos(kd * 0.7)};
  }
  r.render(loads, rng, img);
  ASSERT_EQ(ex.measure(img.view(), {1, 0}), MeasureStatus::kOk);
  for (std::size_t k = 0; k < loads.size(); ++k) {
    const ElementReading& m = ex.readings()[k];
    const Vec2 c = r.noiseless_centroid_px(k);
    EXPECT_NEAR(m.ux_mm, (c.x - cal.elements[k].zero_px.x) * cal.mm_per_px, 0.0005) << k;
    EXPECT_NEAR(m.uy_mm, (c.y - cal.elements[k].zero_px.y) * cal.mm_per_px, 0.0005) << k;
  }
}

// The image's increment over the no-load frame at pixel (x, y).
double increment_at(const Image& img, const Image& empty, double x, double y) {
  const int px = static_cast<int>(std::lround(x));
  const int py = static_cast<int>(std::lround(y));
  return static_cast<double>(img.get(px, py)) - static_cast<double>(empty.get(px, py));
}

// Eq. 3-4 of the paper on element k's disk of a noiseless image, over the no-load frame.
Vec2 image_centroid(const Image& img, const Image& empty, const ElementCalibration& e) {
  double sum = 0, sx = 0, sy = 0;
  for (const DiskRow& row : disk_rows(e.center_px, e.radius_px)) {
    for (int x = row.x0; x < row.x1; ++x) {
      const double dg =
          static_cast<double>(img.get(x, row.y)) - static_cast<double>(empty.get(x, row.y));
      sum += dg;
      sx += dg * x;
      sy += dg * row.y;
    }
  }
  return {sx / sum, sy / sum};
}

// The feeler model on a noiseless camera: the no-load frame, and a frame with a load on the
// centre element only.
struct NoiselessFeelers {
  CameraParams cam = noiseless_camera();
  SensorOpticsParams opt = feelers();
  Calibration cal = calibration(cam, opt);
  Renderer renderer{cal, cam, opt, 7};
  util::Random rng{1};
  std::vector<ElementLoad> loads = std::vector<ElementLoad>(41);
  Image empty, img;

  NoiselessFeelers() { renderer.render(loads, rng, empty); }
  const Image& render_centre(const ElementLoad& load) {
    loads[0] = load;
    renderer.render(loads, rng, img);
    return img;
  }
};

struct ShearCase {
  double ux_mm, uy_mm;
};

class FeelerShear : public ::testing::TestWithParam<ShearCase> {};

// The cluster follows the shear, and further than the deflection (the leading cones carry more of
// the load); the truth's centroid is eq. 3-4 on the noiseless image.
TEST_P(FeelerShear, CentroidMovesWithTheShearAndIsTheTruths) {
  const ShearCase sc = GetParam();
  NoiselessFeelers f;
  const ElementCalibration& e = f.cal.elements[0];
  EXPECT_EQ(f.renderer.noiseless_centroid_px(0).x, e.zero_px.x);  // no light: the spot's centre
  const Image& img = f.render_centre({0.8, sc.ux_mm, sc.uy_mm});
  const Vec2 truth = f.renderer.noiseless_centroid_px(0);
  const Image& empty = f.empty;
  const Calibration& cal = f.cal;
  const Vec2 seen = image_centroid(img, empty, e);
  EXPECT_NEAR(seen.x, truth.x, 0.02);
  EXPECT_NEAR(seen.y, truth.y, 0.02);
  const double u = std::hypot(sc.ux_mm, sc.uy_mm) / cal.mm_per_px;
  const Vec2 shift{truth.x - e.zero_px.x, truth.y - e.zero_px.y};
  const double along = (shift.x * sc.ux_mm + shift.y * sc.uy_mm) / std::hypot(sc.ux_mm, sc.uy_mm);
  const double across = (shift.y * sc.ux_mm - shift.x * sc.uy_mm) / std::hypot(sc.ux_mm, sc.uy_mm);
  EXPECT_GT(along, u + 0.1);
  EXPECT_LT(along, u + 2.0);
  EXPECT_NEAR(across, 0.0, 0.02);
}

INSTANTIATE_TEST_SUITE_P(Shears, FeelerShear,
                         ::testing::Values(ShearCase{0.02, 0.0}, ShearCase{-0.02, 0.0},
                                           ShearCase{0.0, 0.03}, ShearCase{0.015, -0.015},
                                           ShearCase{-0.06, 0.01}));

struct OnsetCase {
  double fz_n;
  bool cones_touch;
};

class FeelerOnset : public ::testing::TestWithParam<OnsetCase> {};

// The paper's order of contact: the column collapses first, the eight cones touch later.
TEST_P(FeelerOnset, TheColumnShowsFirstThenTheCones) {
  const OnsetCase oc = GetParam();
  NoiselessFeelers f;
  const Image& img = f.render_centre({oc.fz_n, 0.0, 0.0});
  const Image& empty = f.empty;
  const SensorOpticsParams& opt = f.opt;
  const Vec2 c = f.cal.elements[0].zero_px;
  EXPECT_GT(increment_at(img, empty, c.x, c.y), 40.0);
  for (int i = 0; i < 8; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 8.0;
    const double x = c.x + opt.feelers.cone_circle_px * std::cos(a);
    const double y = c.y + opt.feelers.cone_circle_px * std::sin(a);
    if (oc.cones_touch) {
      EXPECT_GT(increment_at(img, empty, x, y), 20.0) << i;
    } else {
      EXPECT_LE(increment_at(img, empty, x, y), 1.0) << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Loads, FeelerOnset,
                         ::testing::Values(OnsetCase{0.05, false}, OnsetCase{0.06, false},
                                           OnsetCase{0.4, true}, OnsetCase{1.5, true}));

TEST(Optics, ElementModelNamesRoundTrip) {
  for (auto m : {ElementModel::kGaussian, ElementModel::kFeelers})
    EXPECT_EQ(element_model_from_string(to_string(m)), m);
  EXPECT_FALSE(element_model_from_string("gauss").has_value());
  EXPECT_EQ(SensorOpticsParams{}.element_model, ElementModel::kGaussian);
}

}  // namespace
}  // namespace tactile::rig
