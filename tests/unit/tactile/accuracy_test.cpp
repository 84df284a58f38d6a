// The foundation's accuracy promise (issue 2): on Gaussian spots of sigma 1.5 to 3.5 px and
// peak 30 to 150 gray levels over a vignetted background, pixel noise sigma 2 and a reference of
// 16 frames, the default estimator's centroid RMS error is at most 1.5 times the Cramer-Rao
// bound, its bias at most 0.005 px, contact is detected exactly and forces follow the curves.
// The same in 16 bits. Issue 38: on elliptical spots (aspect 2) kGaussianAxes is within 1.1 times
// the bound per axis and clearly better than kGaussian's round weight; on flat-topped spots (a
// plateau with Gaussian shoulders) both stay where they are today. Fixed seeds: the figures are
// the same on every run.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "synthetic.hpp"
#include "tactile/extractor.hpp"

namespace tactile {
namespace {

struct Setting {
  int bit_depth;
  double sigma;
  double peak;
  testing::SpotShape shape = testing::SpotShape::kGaussian;
  double aspect = 1;  // kElliptical: sigma along y over sigma along x
  CentroidEstimator estimator = ExtractorOptions{}.estimator;
};

// Cramer-Rao bound per axis for one frame in white noise, from the spot's continuous profile
// (no pixelation, no reference noise): sigma_n / sqrt(I) with the Fisher information
// I = (A / sigma_n)^2 * integral of (df/dx)^2 over the plane, f the profile of peak 1.
//   Gaussian, widths sx, sy: along x I = (A / sigma_n)^2 pi sy / (2 sx).
//   Plateau of radius R with Gaussian shoulders sigma: I = (A / sigma_n)^2 pi (1/2 + R sqrt(pi)
//   / (4 sigma)) along either axis. R = 0 and sx = sy give the textbook sqrt(2 / pi) sigma_n / A.
Vec2 simple_bound(const Setting& s, double noise_sigma) {
  const double a = s.peak / noise_sigma;
  if (s.shape == testing::SpotShape::kFlatTop) {
    const double i = a * a * M_PI * (0.5 + 3.0 * std::sqrt(M_PI) / (4 * s.sigma));
    return {1 / std::sqrt(i), 1 / std::sqrt(i)};
  }
  const double sx = s.sigma;
  const double sy = s.shape == testing::SpotShape::kElliptical ? s.aspect * s.sigma : s.sigma;
  return {1 / std::sqrt(a * a * M_PI * sy / (2 * sx)), 1 / std::sqrt(a * a * M_PI * sx / (2 * sy))};
}

struct Stats {
  double rms = 0;    // worse axis, px
  double bias = 0;   // worst of |mean error| and |pull toward the disk centre over 1 px|
  double crb = 0;    // per axis, px (the larger)
  double ratio = 0;  // worse axis of RMS error over that axis's bound
  int contact_errors = 0;
  int samples = 0;
};

// Least-squares fit err = a + k * offset; returns max(|a|, |k| * 1 px).
double bias_of(const std::vector<double>& err, const std::vector<double>& off) {
  const double n = static_cast<double>(err.size());
  double se = 0, so = 0, soo = 0, seo = 0;
  for (std::size_t i = 0; i < err.size(); ++i) {
    se += err[i];
    so += off[i];
    soo += off[i] * off[i];
    seo += err[i] * off[i];
  }
  const double k = (n * seo - so * se) / (n * soo - so * so);
  const double a = (se - k * so) / n;
  return std::max(std::abs(a), std::abs(k));
}

Stats run(const Setting& s, int frames, std::uint64_t seed) {
  testing::SceneOptions o;
  o.bit_depth = s.bit_depth;
  o.noise_sigma = 2.0;
  // Disks hold the spot out to 3.5 of its widths (elliptical aspect 2: sigma_y up to 4 px).
  const double radius = s.shape == testing::SpotShape::kGaussian ? 14.0 : 18.0;
  Calibration cal = testing::grid_calibration(o, 8, 5, 60.0, radius);
  const double scale = testing::level_scale(s.bit_depth);
  cal.contact_on = 150 * scale;  // the faintest spot here (sigma 1.5, peak 30) gives G ~ 250
  cal.contact_off = 80 * scale;
  if (s.shape != testing::SpotShape::kGaussian) {
    // The larger disks' noise alone comes near 150; the faintest shape here gives G ~ 1400.
    cal.contact_on = 500 * scale;
    cal.contact_off = 300 * scale;
  }
  ExtractorOptions opt;
  opt.estimator = s.estimator;
  opt.reference_frames = 16;
  Extractor ex(cal, opt);

  util::Random rng(seed);
  Image img;
  const testing::SceneRenderer scene(o, &cal);

  std::vector<double> ex_err, ey_err, ox, oy;
  Stats st;
  for (int f = 0; f < frames; ++f) {
    // A fresh reference every 20 frames: the reference's own noise is a fixed pattern for as
    // long as it is in use, and the bias is the estimator's, averaged over references.
    if (f % 20 == 0) {
      ex.begin_reference();
      for (int i = 0; i < 16; ++i) {
        scene.render({}, rng, img);
        ex.add_reference_frame(img.view());
      }
      EXPECT_TRUE(ex.has_reference());
    }
    std::vector<testing::Spot> spots;
    std::vector<bool> pressed(cal.elements.size());
    std::vector<Vec2> truth(cal.elements.size());
    for (std::size_t e = 0; e < cal.elements.size(); ++e) {
      pressed[e] = ((e + static_cast<std::size_t>(f)) % 4) != 0;  // a quarter stay untouched
      if (!pressed[e]) continue;
      truth[e] = cal.elements[e].center_px + Vec2{rng.uniform(-1, 1), rng.uniform(-1, 1)};
      testing::Spot spot{truth[e], s.peak, s.sigma};
      spot.shape = s.shape;
      spot.sigma_y = s.aspect * s.sigma;
      spots.push_back(spot);
    }
    scene.render(spots, rng, img);
    // Each frame on its own (no displacement needed here).
    ex.forget_previous();
    EXPECT_EQ(ex.measure(img.view(), {static_cast<std::uint64_t>(f), 0}), MeasureStatus::kOk);
    for (std::size_t e = 0; e < cal.elements.size(); ++e) {
      const ElementReading& r = ex.readings()[e];
      if (r.contact != pressed[e]) ++st.contact_errors;
      if (!r.contact || !pressed[e]) continue;
      EXPECT_DOUBLE_EQ(r.fz, cal.normal_curve(r.G));
      ex_err.push_back(r.x_px - truth[e].x);
      ey_err.push_back(r.y_px - truth[e].y);
      ox.push_back(truth[e].x - cal.elements[e].center_px.x);
      oy.push_back(truth[e].y - cal.elements[e].center_px.y);
    }
  }
  double sx = 0, sy = 0;
  for (std::size_t i = 0; i < ex_err.size(); ++i) {
    sx += ex_err[i] * ex_err[i];
    sy += ey_err[i] * ey_err[i];
  }
  const double n = static_cast<double>(ex_err.size());
  st.samples = static_cast<int>(ex_err.size());
  st.rms = std::sqrt(std::max(sx, sy) / n);
  st.bias = std::max(bias_of(ex_err, ox), bias_of(ey_err, oy));
  const Vec2 crb = simple_bound(s, o.noise_sigma);
  st.crb = std::max(crb.x, crb.y);
  st.ratio = std::max(std::sqrt(sx / n) / crb.x, std::sqrt(sy / n) / crb.y);
  return st;
}

class Accuracy : public ::testing::TestWithParam<Setting> {};

TEST_P(Accuracy, DefaultEstimatorNearTheCramerRaoBound) {
  const Setting s = GetParam();
  // Enough frames that the bias estimate's standard error is about 0.001 px: the error's spread
  // falls with the peak, so bright spots need fewer frames.
  const int frames = std::max(40, static_cast<int>(320 * (30 / s.peak) * (30 / s.peak)));
  const Stats st = run(s, std::getenv("ACC_FRAMES") ? std::atoi(std::getenv("ACC_FRAMES")) : frames,
                       static_cast<std::uint64_t>(1000 * s.bit_depth + s.sigma * 10 + s.peak));
  RecordProperty("rms_over_crb", std::to_string(st.rms / st.crb));
  RecordProperty("bias_px", std::to_string(st.bias));
  std::printf(
      "depth %2d sigma %.1f peak %5.1f: rms %.4f px = %.2f x CRB, bias %.4f px, %d samples\n",
      s.bit_depth, s.sigma, s.peak, st.rms, st.rms / st.crb, st.bias, st.samples);
  EXPECT_EQ(st.contact_errors, 0);
  EXPECT_LE(st.rms, 1.5 * st.crb);
  EXPECT_LE(st.bias, 0.005);
}

std::vector<Setting> settings() {
  std::vector<Setting> out;
  for (int depth : {8, 16})
    for (double sigma : {1.5, 2.5, 3.5})
      for (double peak : {30.0, 75.0, 150.0})
        out.push_back({depth, sigma, peak});
  return out;
}

INSTANTIATE_TEST_SUITE_P(GaussianSpots, Accuracy, ::testing::ValuesIn(settings()),
                         [](const ::testing::TestParamInfo<Setting>& p) {
                           return "bits" + std::to_string(p.param.bit_depth) + "_sigma" +
                                  std::to_string(static_cast<int>(p.param.sigma * 10)) + "_peak" +
                                  std::to_string(static_cast<int>(p.param.peak));
                         });

// Issue 38: spots that are not round Gaussians, measured by kGaussian and kGaussianAxes on the
// same frames (the same seed draws the same spots and noise).
struct ShapeSetting {
  testing::SpotShape shape;
  double sigma;
  double aspect;
  double peak;  // noise sigma 2: peak-to-noise 25 and 75
};

Stats run_shape(const ShapeSetting& s, CentroidEstimator e) {
  const Setting setting{8, s.sigma, s.peak, s.shape, s.aspect, e};
  // Enough frames that the fitted pull's standard error is about 0.0007 px (the error's spread
  // falls with the peak): 450 frames at peak-to-noise 25, 50 at 75.
  const int frames = std::max(50, static_cast<int>(450 * (50 / s.peak) * (50 / s.peak)));
  return run(setting, frames, static_cast<std::uint64_t>(100 * s.sigma + s.aspect * 10 + s.peak));
}

void print(const char* what, const ShapeSetting& s, const Stats& st) {
  std::printf(
      "%-13s %s sigma %.1f aspect %.1f peak %5.1f: rms %.4f px = %.3f x CRB, bias %.4f px, "
      "%d samples\n",
      what, s.shape == testing::SpotShape::kFlatTop ? "flat-top  " : "elliptical", s.sigma,
      s.aspect, s.peak, st.rms, st.ratio, st.bias, st.samples);
}

class ShapeAccuracy : public ::testing::TestWithParam<ShapeSetting> {};

TEST_P(ShapeAccuracy, PerAxisWidthsHoldOnEllipticalSpots) {
  const ShapeSetting s = GetParam();
  const Stats round = run_shape(s, CentroidEstimator::kGaussian);
  const Stats axes = run_shape(s, CentroidEstimator::kGaussianAxes);
  print("gaussian", s, round);
  print("gaussian-axes", s, axes);
  EXPECT_EQ(axes.contact_errors, 0);
  EXPECT_LE(axes.bias, 0.002);
  if (s.shape == testing::SpotShape::kElliptical) {
    // The bound here leaves out the reference's own noise (16 frames: 3 %) and pixelation.
    EXPECT_LE(axes.ratio, 1.1);
    EXPECT_LE(axes.rms, (s.aspect >= 2 ? 0.93 : 0.99) * round.rms);
  } else {
    // Flat-topped spots: no Gaussian weight is matched to them (docs/benchmarks.md, issue 38).
    // Both estimators stay within a third of the bound, and per-axis widths cost little.
    EXPECT_LE(round.ratio, 1.35);
    EXPECT_LE(axes.ratio, 1.35);
    EXPECT_LE(axes.rms, 1.05 * round.rms);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, ShapeAccuracy,
    ::testing::Values(ShapeSetting{testing::SpotShape::kElliptical, 1.5, 2.0, 50},
                      ShapeSetting{testing::SpotShape::kElliptical, 2.0, 2.0, 150},
                      ShapeSetting{testing::SpotShape::kElliptical, 2.0, 1.5, 50},
                      ShapeSetting{testing::SpotShape::kFlatTop, 1.5, 1.0, 50},
                      ShapeSetting{testing::SpotShape::kFlatTop, 2.5, 1.0, 150}),
    [](const ::testing::TestParamInfo<ShapeSetting>& p) {
      return std::string(p.param.shape == testing::SpotShape::kFlatTop ? "flat_top"
                                                                       : "elliptical") +
             "_sigma" + std::to_string(static_cast<int>(p.param.sigma * 10)) + "_aspect" +
             std::to_string(static_cast<int>(p.param.aspect * 10)) + "_peak" +
             std::to_string(static_cast<int>(p.param.peak));
    });

}  // namespace
}  // namespace tactile
