#pragma once

// Scenes of the extraction benchmarks: the paper's 41-element layout on a 640 x 480 image,
// spots of known position on chosen elements, and the methods compared.
#include <cstdint>
#include <string>
#include <vector>

#include "synthetic.hpp"
#include "tactile/calibration.hpp"
#include "tactile/extractor.hpp"

namespace tactile::bench {

// 41 elements in rings of 1, 8, 16 and 16 (radii 0, 55, 115 and 180 px) around the image
// centre, each a disk of radius_px; the curves and thresholds of testing::grid_calibration,
// noise_floor = floor_sigmas * o.noise_sigma (in the image's gray levels).
Calibration dome_calibration(const testing::SceneOptions& o, double radius_px = 14.0,
                             double floor_sigmas = 2.0);

// The element indices in the order they are pressed when a scene has k contacts: spread over
// the rings, the same for every run.
std::vector<std::size_t> press_order(std::size_t elements);

// One way to get centroids: a core estimator with its options, the OpenCV baseline, or the
// pixel-sum floor (no centroid; its cost is the floor of any method).
struct Method {
  enum class Kind { kCore, kOpenCv, kFloor };
  std::string name;  // as in the CSV and the plot
  Kind kind = Kind::kCore;
  CentroidEstimator estimator = CentroidEstimator::kGaussian;
  double floor_sigmas = 2.0;  // noise_floor of the calibration, in noise sigmas
  double window_margin_px = 2.0;
  double gaussian_reach_sigmas = 3.5;
  bool is_default = false;  // the Extractor's default configuration
};

// The methods of the comparison, the default estimator first.
std::vector<Method> methods();
const Method* find_method(const std::string& name);

ExtractorOptions options_for(const Method& m);

}  // namespace tactile::bench
