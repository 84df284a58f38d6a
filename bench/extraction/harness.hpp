#pragma once

// The accuracy and slip harness: synthetic frames with known truth, measured by every method
// of scene.hpp on the same frames (docs/benchmarks.md).
#include <cstdint>
#include <string>
#include <vector>

#include "scene.hpp"
#include "synthetic.hpp"

namespace tactile::bench {

// One accuracy condition.
struct SpotSetting {
  testing::SpotShape shape = testing::SpotShape::kGaussian;
  double sigma = 2.5;        // px (elliptical: along x; along y it is `aspect` times this)
  double pnr = 50;           // peak over read-noise sigma
  int depth = 8;             // bits per pixel
  bool shot_noise = false;   // Poisson noise, as much as the read noise at the background
  double flat_radius = 3.0;  // flat-topped spots: radius of the plateau, px
  double aspect = 1.5;       // elliptical spots: sigma along y over sigma along x

  double peak() const;             // gray levels, 8-bit units
  double noise_sigma() const;      // read noise, gray levels, 8-bit units
  std::string shape_name() const;  // "elliptical" for aspect 1.5, else "elliptical-a<aspect>"
};

// Cramer-Rao bound per axis (px) for the position of `s` from one frame and its
// reference_frames-frame reference, with per-pixel unknown background (so the reference's own
// noise counts), read noise, shot noise and quantisation (as uniform noise of 1/12 level^2),
// over the pixels of a disk of radius `radius`; averaged over sub-pixel positions.
struct Bound {
  double x = 0;
  double y = 0;
};
Bound cramer_rao(const SpotSetting& s, double radius, int reference_frames);
// The textbook Cramer-Rao bound for a Gaussian spot in white noise: sqrt(2/pi) sigma_n / A.
double cramer_rao_simple(const SpotSetting& s);

// Accumulates centroid errors against truth and fits, per axis,
//   error = a + k * offset + b * sin(2 pi x) + c * cos(2 pi x),
// offset = true position - disk centre (the pull toward the disk centre is k * offset) and x the
// true position (the pixel-phase bias is the sinusoid). bias = the largest of |a|, |k| x 1 px
// and the sinusoid's amplitude over both axes.
class ErrorStats {
 public:
  void add(double ex, double ey, double off_x, double off_y, double true_x, double true_y);
  void add_miss() { ++misses_; }
  std::int64_t samples() const { return n_; }
  std::int64_t misses() const { return misses_; }
  double rms_x() const;
  double rms_y() const;
  double bias() const;
  double bias_se() const;  // standard error of the largest fitted term

 private:
  struct Axis {
    double xtx[4][4] = {};
    double xte[4] = {};
    double ee = 0;
  };
  static void add_axis(Axis& a, double e, double off, double pos);
  static void solve(const Axis& a, std::int64_t n, double coef[4], double se[4]);
  Axis ax_;
  Axis ay_;
  std::int64_t n_ = 0;
  std::int64_t misses_ = 0;
};

struct AccuracyRow {
  std::string method;
  SpotSetting setting;
  int frames = 0;
  std::int64_t samples = 0;
  std::int64_t misses = 0;
  double rms_x = 0, rms_y = 0, bias = 0, bias_se = 0;
  Bound crb;
  double crb_simple = 0;
  double rms() const { return std::max(rms_x, rms_y); }
  double ratio() const { return std::max(rms_x / crb.x, rms_y / crb.y); }
};

// Measures every method on `frames` frames of one setting (a grid of elements, every one
// pressed, a fresh 16-frame reference every 40 frames).
std::vector<AccuracyRow> run_accuracy(const SpotSetting& s, const std::vector<Method>& methods,
                                      int frames, std::uint64_t seed);

// --- slip statistics (dr = 0.004 mm per frame, mm_per_px 0.025: dr = 0.16 px) ---------------

inline constexpr double kDrMm = 0.004;

struct FalseSlipRow {
  std::string method;
  double noise_sigma = 0;  // gray levels
  double peak = 0;         // gray levels
  std::int64_t element_frames = 0;
  std::int64_t false_slips = 0;
  double centroid_sigma_px = 0;  // per axis, frame to frame, measured
  double predicted = 0;          // exp(-dr^2 / (4 sigma^2)), limits.md
  double rate() const {
    return element_frames > 0
               ? static_cast<double>(false_slips) / static_cast<double>(element_frames)
               : 0;
  }
};
// A still contact on all 41 elements of the dome (Gaussian spots of sigma 2.5 px, the given
// peak) for `frames` frames at the given pixel noise; a slip is |d| > dr on a frame with a
// displacement.
std::vector<FalseSlipRow> run_false_slips(const std::vector<Method>& methods, double noise_sigma,
                                          double peak, int frames, std::uint64_t seed);

struct DelayRow {
  std::string method;
  double speed_dr = 0;  // slip speed, multiples of dr per frame
  std::int64_t trials = 0;
  std::int64_t within_1 = 0;         // detected on the first frame that moved
  std::int64_t within_2 = 0;         // on the first or second
  std::int64_t undetected = 0;       // not while moving (10 frames, fewer for fast slips)
  std::int64_t early = 0;            // a slip reported on the still frames before the onset
  double p50 = 0, p99 = 0, max = 0;  // delay in frames, 1 = the first moving frame
};
// Trials on all 41 elements at once: 5 still frames, then each spot moves at speed_dr * dr per
// frame in its own random direction for 10 frames, or as many as keep its travel within 8 px
// (sigma 2.5 px, peak 100, noise 2).
std::vector<DelayRow> run_delays(const std::vector<Method>& methods, double speed_dr, int trials,
                                 std::uint64_t seed);

}  // namespace tactile::bench
