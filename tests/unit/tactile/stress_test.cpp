// Numerical stress: random calibrations (extreme curves and thresholds, disks from one pixel to
// the largest allowed) and random frames (all zero, saturated, one bright pixel, checkerboards,
// increments below the reference, noise, spots), with duplicated, reversed and jumping sequence
// numbers, through every estimator, both pixel depths and both kernel sets. After every frame:
// no NaN or infinity, G not negative, a centroid inside its disk, forces that follow the curves
// (so monotonic in G and in u), contact that obeys the hysteresis, and displacement only when in
// contact in this frame and the previous one. The AVX2 and portable kernels must agree exactly on
// everything but kGaussian's rounding.
//
// Fixed seeds. TACTILE_STRESS_FRAMES sets the frames per seed (default 300; the "slow" test runs
// 25,000 per seed, over 100,000 frames in all).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

#include "synthetic.hpp"
#include "tactile/extractor.hpp"

namespace tactile {
namespace {

int frames_per_seed() {
  const char* env = std::getenv("TACTILE_STRESS_FRAMES");
  return env != nullptr ? std::max(1, std::atoi(env)) : 300;
}

PiecewiseLinear random_curve(util::Random& rng) {
  const int n = 2 + static_cast<int>(rng.below(5));
  std::vector<double> x{0};
  std::vector<double> y{0};
  for (int i = 1; i < n; ++i) {
    // Steps from a millionth to a million, flat stretches and cliffs.
    x.push_back(x.back() + std::pow(10.0, rng.uniform(-6, 6)));
    const double r = rng.uniform();
    y.push_back(y.back() + (r < 0.25 ? 0.0 : std::pow(10.0, rng.uniform(-6, 6))));
  }
  return {x, y};
}

Calibration random_calibration(util::Random& rng, int depth) {
  Calibration cal;
  cal.sensor_id = "stress";
  cal.width = 8 + static_cast<int>(rng.below(90));
  cal.height = 8 + static_cast<int>(rng.below(70));
  cal.bit_depth = depth;
  const double max_gray = depth == 8 ? 255 : 65535;
  cal.mm_per_px = std::pow(10.0, rng.uniform(-4, 1));
  cal.noise_floor = rng.uniform() < 0.2 ? 0.0 : rng.uniform(0, max_gray / 8);
  cal.contact_on = std::pow(10.0, rng.uniform(-3, std::log10(max_gray) + 4));
  cal.contact_off = cal.contact_on * rng.uniform();
  cal.normal_curve = random_curve(rng);
  cal.shear_curve = random_curve(rng);
  const int n = 1 + static_cast<int>(rng.below(8));
  for (int i = 0; i < n; ++i) {
    ElementCalibration e;
    e.id = static_cast<std::uint32_t>(i * 7 + 3);
    const double max_r = (std::min(cal.width, cal.height) - 1) / 2.0;
    if (rng.uniform() < 0.1) {
      // A one-pixel disk: radius 0 on a pixel centre.
      e.radius_px = 0;
      e.center_px = {static_cast<double>(rng.below(static_cast<std::uint64_t>(cal.width))),
                     static_cast<double>(rng.below(static_cast<std::uint64_t>(cal.height)))};
    } else {
      // At least 0.75 px: every such disk holds a pixel centre.
      e.radius_px = rng.uniform(0.75, std::min(max_r, 20.0));
      e.center_px = {rng.uniform(e.radius_px - 0.5, cal.width - 0.5 - e.radius_px),
                     rng.uniform(e.radius_px - 0.5, cal.height - 0.5 - e.radius_px)};
    }
    e.zero_px = e.center_px;
    cal.elements.push_back(e);
  }
  return cal;
}

enum class FrameKind {
  kZero,
  kSaturated,
  kOnePixel,
  kCheckerboard,
  kBelowReference,
  kNoise,
  kSpots,
  kReferenceCopy,
  kCount
};

// Fills `img` with one kind of frame around the reference level `ref`.
void random_frame(util::Random& rng, const Calibration& cal, std::uint32_t ref, FrameKind kind,
                  Image& img) {
  const std::uint32_t max_gray = cal.bit_depth == 8 ? 255 : 65535;
  const auto clamp = [&](double v) {
    return static_cast<std::uint32_t>(
        std::clamp(std::round(v), 0.0, static_cast<double>(max_gray)));
  };
  const int period = 1 + static_cast<int>(rng.below(3));
  for (int y = 0; y < cal.height; ++y) {
    for (int x = 0; x < cal.width; ++x) {
      std::uint32_t v = ref;
      switch (kind) {
        case FrameKind::kZero:
          v = 0;
          break;
        case FrameKind::kSaturated:
          v = max_gray;
          break;
        case FrameKind::kCheckerboard:
          v = ((x / period + y / period) % 2) != 0 ? max_gray : 0;
          break;
        case FrameKind::kBelowReference:
          v = clamp(ref * rng.uniform(0, 1));
          break;
        case FrameKind::kNoise:
          v = clamp(rng.uniform(0, max_gray));
          break;
        default:
          break;
      }
      img.set(x, y, v);
    }
  }
  if (kind == FrameKind::kOnePixel) {
    img.set(static_cast<int>(rng.below(static_cast<std::uint64_t>(cal.width))),
            static_cast<int>(rng.below(static_cast<std::uint64_t>(cal.height))), max_gray);
  }
  if (kind == FrameKind::kSpots) {
    for (const ElementCalibration& e : cal.elements) {
      if (rng.uniform() < 0.3) continue;
      testing::Spot s;
      s.center = e.center_px + Vec2{rng.uniform(-2, 2), rng.uniform(-2, 2)};
      s.sigma = rng.uniform(0.3, 6);
      s.peak = rng.uniform(0, max_gray);
      for (int y = 0; y < cal.height; ++y)
        for (int x = 0; x < cal.width; ++x)
          img.set(x, y, clamp(img.get(x, y) + testing::spot_at(s, x, y)));
    }
  }
}

// Checks every invariant of one frame's readings given the previous measured frame's (none
// when previous_valid is false) and the gap to it in frame periods (0: too long, repeated or
// backwards, so no displacement).
void check_readings(const Extractor& ex, const std::vector<ElementReading>& previous,
                    bool previous_valid, std::uint32_t gap, std::string_view what) {
  const Calibration& cal = ex.calibration();
  const auto rd = ex.readings();
  ASSERT_EQ(rd.size(), cal.elements.size());
  for (std::size_t i = 0; i < rd.size(); ++i) {
    const ElementReading& r = rd[i];
    const ElementCalibration& e = cal.elements[i];
    SCOPED_TRACE(std::string(what) + " element " + std::to_string(e.id));
    ASSERT_EQ(r.id, e.id);
    for (double v : {r.G, r.x_px, r.y_px, r.dx_mm, r.dy_mm, r.ux_mm, r.uy_mm, r.fx, r.fy, r.fz})
      ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(r.G, 0.0);
    const bool was = previous_valid && previous[i].contact;
    if (r.contact) {
      ASSERT_GE(r.G, was ? cal.contact_off : cal.contact_on);
      ASSERT_LE(std::hypot(r.x_px - e.center_px.x, r.y_px - e.center_px.y), e.radius_px + 1e-9);
      ASSERT_EQ(r.fz, cal.normal_curve(r.G));
      ASSERT_EQ(r.fx, cal.shear_curve.odd(r.ux_mm));
      ASSERT_EQ(r.fy, cal.shear_curve.odd(r.uy_mm));
    } else {
      // Out of contact: below the threshold, or nothing at all (a zero G with contact.off 0).
      ASSERT_TRUE(r.G < (was ? cal.contact_off : cal.contact_on) || r.G == 0);
      for (double v : {r.x_px, r.y_px, r.ux_mm, r.uy_mm, r.fx, r.fy, r.fz})
        ASSERT_EQ(v, 0.0);
    }
    if (r.has_displacement) {
      ASSERT_TRUE(r.contact && was);
      ASSERT_GE(gap, 1U);  // 0 means no valid predecessor
      ASSERT_NEAR(r.dx_mm, (r.x_px - previous[i].x_px) * cal.mm_per_px / gap,
                  1e-9 * (1 + std::abs(r.dx_mm)));
    } else {
      ASSERT_FALSE(r.contact && was && gap >= 1);
      ASSERT_EQ(r.dx_mm, 0.0);
      ASSERT_EQ(r.dy_mm, 0.0);
    }
  }
}

// Forces are monotonic in G and u: over every (G, F_z) and (u, F) pair seen.
void check_monotonic(std::vector<std::pair<double, double>> pairs, std::string_view what) {
  std::sort(pairs.begin(), pairs.end());
  for (std::size_t k = 1; k < pairs.size(); ++k) {
    ASSERT_LE(pairs[k - 1].second, pairs[k].second) << what << " at " << pairs[k].first;
  }
}

class Stress : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(Stress, RandomCalibrationsFramesAndSequences) {
  util::Random rng(GetParam());
  const int frames = frames_per_seed();
  int done = 0;
  while (done < frames) {
    const int depth = rng.uniform() < 0.5 ? 8 : 16;
    const Calibration cal = random_calibration(rng, depth);
    ExtractorOptions opt;
    opt.estimator = static_cast<CentroidEstimator>(rng.below(4));
    opt.reference_frames = 1 + static_cast<int>(rng.below(3));
    opt.reference_spot_check = false;
    opt.max_gap_frames = 1 + static_cast<std::uint32_t>(rng.below(5));
    opt.gaussian_reach_sigmas = rng.uniform(1, 5);
    opt.window_margin_px = rng.uniform(0, 4);
    Extractor fast(cal, opt);
    opt.portable_kernels = true;
    Extractor portable(cal, opt);
    const PixelFormat fmt = depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
    Image img(cal.width, cal.height, fmt);
    const std::uint32_t max_gray = depth == 8 ? 255 : 65535;
    const auto ref_level = static_cast<std::uint32_t>(rng.below(max_gray + 1));
    for (int k = 0; k < opt.reference_frames; ++k) {
      random_frame(rng, cal, ref_level,
                   rng.uniform() < 0.5 ? FrameKind::kReferenceCopy : FrameKind::kBelowReference,
                   img);
      fast.add_reference_frame(img.view());
      portable.add_reference_frame(img.view());
    }
    ASSERT_EQ(fast.has_reference(), portable.has_reference());
    if (!fast.has_reference()) continue;  // refused for motion: a new calibration

    std::vector<ElementReading> previous(cal.elements.size());
    bool previous_valid = false;
    std::uint64_t seq = rng.below(1000);
    std::uint64_t last_seq = 0;
    std::vector<std::pair<double, double>> g_fz;
    std::vector<std::pair<double, double>> u_f;
    const int run = 1 + static_cast<int>(rng.below(60));
    for (int f = 0; f < run && done < frames; ++f, ++done) {
      random_frame(rng, cal, ref_level,
                   static_cast<FrameKind>(rng.below(static_cast<std::uint64_t>(FrameKind::kCount))),
                   img);
      // Sequence numbers: mostly the next, sometimes repeated, backwards or far ahead.
      const double r = rng.uniform();
      if (r < 0.70) {
        seq += 1;
      } else if (r < 0.78) {
        // repeated
      } else if (r < 0.86) {
        seq = seq > 3 ? seq - 3 : 0;
      } else if (r < 0.94) {
        seq += 2 + rng.below(6);
      } else {
        seq += rng.below(1ULL << 40);
      }
      const FrameInfo info{seq, static_cast<std::int64_t>(rng.next())};
      const std::uint32_t gap =
          previous_valid && seq > last_seq
              ? static_cast<std::uint32_t>(std::min<std::uint64_t>(seq - last_seq, 1000))
              : 0;
      ASSERT_EQ(fast.measure(img.view(), info), MeasureStatus::kOk);
      ASSERT_EQ(portable.measure(img.view(), info), MeasureStatus::kOk);
      const bool gap_ok = gap >= 1 && gap <= opt.max_gap_frames;
      check_readings(fast, previous, previous_valid, gap_ok ? gap : 0,
                     "seed " + std::to_string(GetParam()) + " frame " + std::to_string(done));
      if (::testing::Test::HasFatalFailure()) return;
      // The two kernel sets agree: exactly, but for kGaussian's floating-point rounding.
      const auto a = fast.readings();
      const auto b = portable.readings();
      for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].contact, b[i].contact);
        ASSERT_EQ(a[i].G, b[i].G);
        ASSERT_EQ(a[i].has_displacement, b[i].has_displacement);
        if (opt.estimator == CentroidEstimator::kGaussian ||
            opt.estimator == CentroidEstimator::kGaussianAxes) {
          ASSERT_NEAR(a[i].x_px, b[i].x_px, 1e-3);
          ASSERT_NEAR(a[i].y_px, b[i].y_px, 1e-3);
        } else {
          ASSERT_EQ(a[i].x_px, b[i].x_px);
          ASSERT_EQ(a[i].y_px, b[i].y_px);
        }
        if (a[i].contact) {
          g_fz.emplace_back(a[i].G, a[i].fz);
          u_f.emplace_back(a[i].ux_mm, a[i].fx);
          u_f.emplace_back(a[i].uy_mm, a[i].fy);
        }
      }
      previous.assign(a.begin(), a.end());
      previous_valid = true;
      last_seq = seq;
      // Now and then a frame of the wrong size or depth: reported, readings untouched.
      if (rng.uniform() < 0.02) {
        Image wrong(cal.width + 1, cal.height, fmt);
        ASSERT_EQ(fast.measure(wrong.view(), {seq + 1, 0}), MeasureStatus::kWrongSize);
        Image other(cal.width, cal.height, depth == 8 ? PixelFormat::kMono16 : PixelFormat::kMono8);
        ASSERT_EQ(fast.measure(other.view(), {seq + 1, 0}), MeasureStatus::kWrongFormat);
        ASSERT_EQ(fast.readings()[0].G, previous[0].G);
      }
    }
    check_monotonic(g_fz, "F_z against G");
    check_monotonic(u_f, "F against u");
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, Stress, ::testing::Values(11, 22, 33, 44));

// The largest disk the calibration allows, 16-bit pixels at full scale: every sum stays exact.
TEST(StressLimits, LargestDiskAtFullScale16Bit) {
  Calibration cal;
  cal.sensor_id = "big";
  cal.width = 2049;
  cal.height = 2049;
  cal.bit_depth = 16;
  cal.mm_per_px = 0.025;
  cal.noise_floor = 3;
  cal.contact_on = 1;
  cal.contact_off = 0.5;
  cal.normal_curve = PiecewiseLinear({0, 1}, {0, 1});
  cal.shear_curve = PiecewiseLinear({0, 1}, {0, 1});
  ElementCalibration e;
  e.id = 1;
  e.center_px = {1024, 1024};
  e.radius_px = kMaxRadiusPx;
  e.zero_px = e.center_px;
  cal.elements.push_back(e);
  const std::int64_t n = disk_pixel_count(e.center_px, e.radius_px);
  for (CentroidEstimator est :
       {CentroidEstimator::kThresholded, CentroidEstimator::kGaussian, CentroidEstimator::kPlain,
        CentroidEstimator::kWindowed, CentroidEstimator::kGaussianAxes}) {
    ExtractorOptions opt;
    opt.reference_frames = 1;
    opt.estimator = est;
    Extractor ex(cal, opt);
    Image img(cal.width, cal.height, PixelFormat::kMono16);  // zeros: the reference
    ASSERT_EQ(ex.add_reference_frame(img.view()).status, ReferenceStatus::kComplete);
    std::fill(img.bytes().begin(), img.bytes().end(), std::uint8_t{0xFF});  // 65535 everywhere
    ASSERT_EQ(ex.measure(img.view(), {1, 0}), MeasureStatus::kOk);
    const ElementReading& r = ex.readings()[0];
    ASSERT_TRUE(r.contact);
    // Exact: n pixels of 65535 - 3 each.
    EXPECT_EQ(r.G, static_cast<double>(n) * (65535 - 3));
    EXPECT_NEAR(r.x_px, 1024, 1e-6) << to_string(est);
    EXPECT_NEAR(r.y_px, 1024, 1e-6) << to_string(est);
    // One bright quadrant: the centroid moves toward it, inside the disk, still finite.
    for (int y = 0; y < cal.height; ++y)
      for (int x = 0; x < cal.width; ++x)
        img.set(x, y, x > 1024 && y > 1024 ? 65535 : 0);
    ASSERT_EQ(ex.measure(img.view(), {2, 0}), MeasureStatus::kOk);
    const ElementReading& q = ex.readings()[0];
    ASSERT_TRUE(q.contact);
    EXPECT_GT(q.x_px, 1024 + 100);
    EXPECT_GT(q.y_px, 1024 + 100);
    EXPECT_LE(std::hypot(q.x_px - 1024, q.y_px - 1024), kMaxRadiusPx);
    EXPECT_TRUE(std::isfinite(q.dx_mm) && std::isfinite(q.fz));
  }
}

}  // namespace
}  // namespace tactile
