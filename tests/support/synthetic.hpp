#pragma once

// Synthetic tactile frames with known truth, for tests and the accuracy harness: a vignetted
// background, bright spots at chosen sub-pixel positions, Gaussian read noise and optional
// shot noise, quantised to 8 or 16 bits.
#include <cstdint>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/image.hpp"
#include "tactile/util/random.hpp"

namespace tactile::testing {

// kFeelers: the paper's element as the rig draws it (docs/rig.md, "The feeler element"), unsheared
// (symmetric: its centroid is its centre), with `peak` the contacts' level.
enum class SpotShape { kGaussian, kElliptical, kFlatTop, kFeelers };

struct Spot {
  Vec2 center;         // true centroid, pixels
  double peak = 100;   // gray levels above background (in 8-bit units; scaled for 16-bit)
  double sigma = 2.0;  // pixels (kElliptical: along x)
  double sigma_y = 0;  // kElliptical: along y (0 means sigma)
  SpotShape shape = SpotShape::kGaussian;
  double flat_radius = 3;       // kFlatTop: radius of the plateau
  double feeler_load_px2 = 40;  // kFeelers: the load as the contact area it collapses, px^2
};

struct SceneOptions {
  int width = 640;
  int height = 480;
  int bit_depth = 8;
  double background = 40;      // gray levels at the image centre (8-bit units)
  double vignetting = 0.35;    // fractional fall-off of the background at the image corners
  double noise_sigma = 2.0;    // read noise, gray levels (8-bit units)
  double shot_noise_gain = 0;  // electrons per gray level; 0 disables shot noise
};

// Scale from 8-bit gray levels to the image's levels (1 or 257).
double level_scale(int bit_depth);

// The noiseless background value at pixel (x, y).
double background_at(const SceneOptions& o, double x, double y);
// A spot's noiseless value at pixel centre (x, y).
double spot_at(const Spot& s, double x, double y);

// Renders into `out` (allocated on first use, reused after). With `only` given, pixels outside
// the bounding boxes of its elements' disks keep the noiseless background (faster: the
// measurement never reads them).
void render(const SceneOptions& o, const std::vector<Spot>& spots, util::Random& rng, Image& out,
            const Calibration* only = nullptr);

// Renders many frames of one scene fast: the noiseless background is computed once, and with a
// calibration given only the bounding boxes of its disks get noise and spots.
class SceneRenderer {
 public:
  explicit SceneRenderer(const SceneOptions& o, const Calibration* only = nullptr);
  void render(const std::vector<Spot>& spots, util::Random& rng, Image& out) const;

 private:
  SceneOptions o_;
  Image background_;
  struct Box {
    int x0, y0, x1, y1;
  };
  std::vector<Box> boxes_;
};

// A calibration with `rows` x `cols` elements on a grid (spacing in pixels, radius in pixels),
// zero_px at each disk centre and the example curves of docs/calibration.md.
Calibration grid_calibration(const SceneOptions& o, int cols, int rows, double spacing,
                             double radius);

}  // namespace tactile::testing
