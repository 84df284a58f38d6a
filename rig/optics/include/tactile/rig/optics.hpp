#pragma once

// The sensor's optics in reverse (docs/rig.md, "Optics"): each element's true normal force and
// shear displacement become a bright spot in the fingertip camera's image, through the inverse
// of the calibration curves the rig writes for the sensor it simulates.
//
// Pure: no I/O, no clocks. render() allocates nothing once the output image has its size.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/geometry.hpp"
#include "tactile/image.hpp"
#include "tactile/util/random.hpp"

namespace tactile::rig {

struct CameraParams {
  double fps = 100.0;
  int width = 640;
  int height = 480;
  int bit_depth = 8;
  double noise_sigma = 2.0;      // read noise, gray levels (8-bit units)
  double shot_noise_gain = 0.0;  // electrons per 8-bit gray level; 0: no shot noise
  double background = 40.0;      // gray level at the image centre (8-bit units)
  double vignetting = 0.35;      // fractional fall-off of the background at the corners
  // Re-noise every pixel of every frame from the noise model (costly: a real-time camera stream
  // with --full-noise). Otherwise the 41 measurement disks get fresh noise each frame, and the
  // rest of the image is:
  // - with live_background, copied row by row from one of kBackgroundBank noisy background
  //   frames drawn once, each row's frame picked at random: a live background as a camera shows
  //   it through the acrylic, at the cost of a copy (the images anyone sees: the cameras);
  // - without, the first frame's, unchanged (the lockstep runner, where only the measurement
  //   reads the images, and it reads only the disks).
  // The disks' pixels are the same in all three: the measurement's figures do not depend on it.
  bool refresh_outside_disks = false;
  bool live_background = true;
};

// What an element's contact looks like in the image (docs/rig.md, "Optics"): a smooth Gaussian
// spot, or the paper's element, one columnar feeler and eight conical feelers whose contacts
// collapse onto the acrylic as a cluster of bright disks.
enum class ElementModel : std::uint8_t { kGaussian, kFeelers };
const char* to_string(ElementModel m);
std::optional<ElementModel> element_model_from_string(std::string_view name);
// The names element_model_from_string accepts, for error messages.
inline constexpr const char* kElementModelNames = "gaussian or feelers";

// The feeler model's geometry and brightness (docs/rig.md, "The feeler element"). Lengths in
// pixels, levels in 8-bit gray levels.
struct FeelerParams {
  double contact_level = 120.0;   // brightness of a collapsed contact over the background
  double column_radius_px = 2.0;  // the columnar feeler's flat contact when fully collapsed
  // The cones touch once the load would collapse this fraction of the column's full area.
  double cone_onset = 0.5;
  double cone_circle_px = 4.5;  // the conical feelers' tips: a circle around the column
  double tilt_share = 0.8;      // load moved from the trailing to the leading cones, at most
  double tilt_mm = 0.04;        // shear displacement at which that transfer is complete
};

// The feeler element's contacts (docs/rig.md, "The feeler element"): the column's, then the eight
// cones' (azimuth i pi / 4), each a disk of area proportional to the load it carries.
struct FeelerContact {
  double x = 0, y = 0;  // centre, image pixels
  double r = 0;         // drawn radius: the contact's own, at least half a pixel
  double level = 0;     // brightness over the background, output gray levels
};
using FeelerCluster = std::array<FeelerContact, 9>;
// The cluster of strength p (summed increment, output gray levels; `scale` from 8-bit levels to
// them) centred at (cx, cy), under the shear displacement (ux, uy) mm.
FeelerCluster feeler_cluster(const FeelerParams& f, double scale, double p, double cx, double cy,
                             double ux_mm, double uy_mm);
// The cluster's noiseless increment at pixel centre (x, y).
double cluster_increment(const FeelerCluster& cluster, double x, double y);

struct SensorOpticsParams {
  ElementModel element_model = ElementModel::kGaussian;
  FeelerParams feelers;
  double mm_per_px = 0.025;
  double disk_radius_px = 14.0;
  // Radius of each ring of element disks in a 480-row image (scaled with the image).
  std::array<double, 4> ring_radius_px{0.0, 60.0, 120.0, 180.0};
  // Spot model: a Gaussian whose peak is spot_peak_ref gray levels (8-bit) when its width is
  // free; the width sqrt(G / (2 pi peak)) is held within [sigma_min, sigma_max], and the peak
  // takes up the rest.
  double spot_peak_ref = 200.0;
  double spot_sigma_min_px = 1.0;
  double spot_sigma_max_px = 5.5;
  double contact_on = 400.0;  // G, 8-bit units
  double contact_off = 250.0;
  double noise_floor_min = 4.0;     // the calibration's noise_floor is the larger of this
  double noise_floor_sigmas = 3.0;  // and this many background noise sigmas
  int reference_frames = 16;        // frames the measurement's no-load reference averages
  // The calibration sensor_node and hand_node are given, against the sensor rendered: a lab's
  // calibration error (docs/rig.md, "Calibration error"). The forces of its normal and shear
  // curves are (1 + error) times the sensor's, every element's centre and zero are moved by
  // layout_offset_px.
  double normal_curve_error = 0;
  double shear_curve_error = 0;
  Vec2 layout_offset_px{0, 0};
};

// Gray-level scale of the image relative to 8-bit units (1 or 257).
double level_scale(int bit_depth);

// The calibration of the simulated sensor (tactile-calibration/1): 41 element disks in rings
// of 1, 8, 16, 16 around the image centre (element k of `normals` in ring order, its azimuth
// from its normal), zero_px at each disk centre, the example curves of docs/calibration.md (G
// scaled to the bit depth), and each element's inward normal.
Calibration make_calibration(const std::string& sensor_id, const CameraParams& cam,
                             const SensorOpticsParams& opt, std::span<const Vec3> normals);

// The calibration the measurement is given for a sensor whose true calibration is `truth`: the
// curves' forces and the layout as SensorOpticsParams' calibration error says. Pure.
Calibration as_calibrated(const Calibration& truth, const SensorOpticsParams& opt);

// What an element's spot shows: its normal force and its shear displacement (mm, along the
// image's columns and rows).
struct ElementLoad {
  double fz_n = 0;
  double ux_mm = 0;
  double uy_mm = 0;
};

// Noisy background frames the renderer draws once and copies rows from (CameraParams).
inline constexpr std::size_t kBackgroundBank = 16;

class Renderer {
 public:
  // Draws a pool of standard normal samples from `noise_seed` and precomputes, per element,
  // the expected measured G of a spot as a function of its drawn strength.
  Renderer(const Calibration& cal, const CameraParams& cam, const SensorOpticsParams& opt,
           std::uint64_t noise_seed);

  // Renders one frame into `out` (sized on first use). Spots whose load did not change keep
  // their cached noiseless pixels; every disk gets fresh noise from the pool at offsets drawn
  // from `rng`. Only the disks' pixels (the measurement's disks S) are drawn: the rest of each
  // disk's bounding box is background like the rest of the image. No allocation once `out` has
  // the calibration's size and format.
  void render(std::span<const ElementLoad> loads, util::Random& rng, Image& out);

  // Expected G the measurement finds for a spot of drawn strength p (sum of its noiseless
  // increments, output gray levels) on element k: background noise, floor and quantisation
  // included.
  double expected_g(std::size_t k, double p) const;
  // The drawn strength whose expected measured G is `g` (0 for g at or below the noise's own).
  double strength_for_g(std::size_t k, double g) const;
  // The paper's eq. 3-4 on element k's noiseless image as last rendered: the increment-weighted
  // centroid of its disk's pixels (the spot's centre when it has no increment), image pixels.
  // The Gaussian model gives the spot's centre, about which its light is symmetric (the feeler
  // model only pays for the pass over the pixels).
  Vec2 noiseless_centroid_px(std::size_t k) const { return centroid_px_[k]; }
  // Spots whose noiseless pixels the last render() recomputed (their load changed).
  std::size_t redrawn_spots() const { return redrawn_; }
  // Noise standard deviation of a background pixel at (x, y), output gray levels.
  double pixel_sigma(double value_levels) const;
  double background_at(double x, double y) const;

  // The columns [x0, x1) of a box row (box-relative) whose centres lie in the disk; empty when
  // x0 == x1.
  struct Span {
    int x0, x1;
  };

 private:
  struct Box {
    int x0, y0, x1, y1;       // inclusive
    std::size_t offset;       // into cache_
    std::size_t span_offset;  // into spans_: one span per row y0..y1
  };
  void draw_spot(std::size_t k, const ElementLoad& load);
  void draw_gaussian(std::size_t k, double p, double cx, double cy);
  void draw_feelers(std::size_t k, double p, double cx, double cy, double ux_mm, double uy_mm);
  void centroid_from_cache(std::size_t k, double cx, double cy);
  template <typename Pixel>
  void noisy_box(std::size_t k, util::Random& rng, Image& out) const noexcept;

  Calibration cal_;
  CameraParams cam_;
  SensorOpticsParams opt_;
  double scale_ = 1;
  double max_level_ = 255;
  std::vector<float> pool_;
  std::vector<Box> boxes_;
  std::vector<Span> spans_;
  std::vector<double> column_exp_;  // draw_spot's per-column factor exp(-(x - cx)^2 / 2 sigma^2)
  std::vector<float> cache_value_;  // noiseless pixel values of every box
  std::vector<float> cache_sigma_;  // their noise sigmas
  std::vector<float> increment_;    // draw_feelers' scratch: one box's increments
  std::vector<Vec2> centroid_px_;   // noiseless_centroid_px of every element
  std::vector<ElementLoad> last_;
  std::vector<bool> drawn_;
  // Per element: expected G at strengths strength_grid_ (monotonic).
  std::vector<double> strength_grid_;
  std::vector<std::vector<double>> g_table_;
  std::vector<float> background_;
  std::vector<float> background_sigma_;  // pixel_sigma of each background pixel
  float read_sigma_ = 0;                 // pixel_sigma of every pixel without shot noise
  // kBackgroundBank noisy background frames, rows of output pixels, and the generator that picks
  // a row from them: apart from the disks' noise, so the disks' pixels do not depend on it.
  std::vector<std::uint8_t> background_bank_;
  util::Random bank_rng_;
  bool first_ = true;
  std::size_t redrawn_ = 0;
};

}  // namespace tactile::rig
