#pragma once

// tactile_calibrate's work, as functions the program and the tests call (docs/calibration.md,
// "Calibration workflow"):
//
//   layout:  frames of a light press (and no-load references) -> the elements' disks, zero
//            positions, ids and normals of a calibration file;
//   measure: frames taken under known loads + a calibration -> a samples CSV (applied load
//            against measured G and u), through the real measurement core;
//   fit:     a samples CSV -> the normal curve g and the shear curve f, with the fit error per
//            element, or a refusal that says why.
//
// Refusals throw std::runtime_error with one line that says what was found and what to do.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/curve.hpp"
#include "tactile/extractor.hpp"
#include "tactile/geometry.hpp"
#include "tactile/image.hpp"

namespace tactile::calibrate {

// Called while long work goes on: `done` of `total` items of `what` ("frames") are finished.
using Progress = std::function<void(std::size_t done, std::size_t total, const char* what)>;

// ---------------------------------------------------------------------------------------------
// layout

enum class ElementOrder {
  kRings,  // rings by radius from the layout centre, inside a ring by azimuth (the rig's order)
  kRows,   // rows top to bottom, inside a row left to right
};

struct LayoutOptions {
  std::string sensor_id;
  double mm_per_px = 0;
  // Refuse unless exactly this many elements are found (0: any number).
  std::size_t expect = 41;
  // Radius of every measurement disk S (pixels); 0: 0.45 times the smallest distance between two
  // elements, rounded down to a half pixel.
  double radius_px = 0;
  // Radii from the layout centre that differ by more than this start a new ring (pixels);
  // 0: the disk radius.
  double ring_gap_px = 0;
  // Elements per ring, innermost first, to check the rings found (empty: no check).
  std::vector<int> ring_counts;
  // The layout centre in the image (the dome's apex); unset: the mean of the element positions.
  std::optional<Vec2> center;
  ElementOrder order = ElementOrder::kRings;
  // Polar angle of each ring on the hemispherical dome, innermost first (degrees). Given: every
  // element's inward normal is (sin t cos a, sin t sin a, cos t) with t its ring's polar angle
  // and a its azimuth. Empty: every normal is [0, 0, 1] for the user to fill in.
  std::vector<double> ring_polar_deg;
  // The fingertip's azimuth of an element is its image azimuth (from +x, the columns, toward +y,
  // the rows), negated when `mirror`, plus this offset (degrees).
  double azimuth_offset_deg = 0;
  bool mirror = false;
  // Calibration settings written with the layout (image gray levels); unset: chosen from the
  // measured pixel noise (docs/calibration.md).
  std::optional<double> noise_floor;
  std::optional<double> contact_on;
  std::optional<double> contact_off;
  // A spot is a connected area of the smoothed increment above 3 noise sigmas holding a pixel
  // above `detect_sigmas` noise sigmas, with at least `min_area` pixels.
  double detect_sigmas = 8.0;
  int min_area = 4;
  // Detections in different frames closer than this are the same element (pixels).
  double merge_px = 4.0;
  CentroidEstimator estimator = CentroidEstimator::kGaussian;
};

// What the layout step looks at. With references, each frame's increment over their mean shows
// the spots (a sequence of lightly pressed frames: each element must be pressed in at least
// one); without, the mean of the frames is one light-press image and its background is
// estimated from the image itself.
struct LayoutInput {
  std::vector<Image> frames;
  std::vector<Image> references;
};

struct FoundElement {
  std::uint32_t id = 0;
  int ring = 0;            // ring (kRings) or row (kRows), from 0
  Vec2 position;           // mean centroid under the light press (= center_px = zero_px)
  double spread_px = 0;    // standard deviation of that mean (0 with one frame)
  double azimuth_deg = 0;  // fingertip azimuth (kRings)
  double radius_from_center = 0;
  double G = 0;            // mean G in the frames where it was in contact
  std::size_t frames = 0;  // frames where it was in contact
};

struct LayoutResult {
  Calibration calibration;
  std::vector<FoundElement> elements;  // in calibration order
  std::vector<int> group_counts;       // elements per ring (or row)
  Vec2 center;                         // the layout centre used for rings and azimuths
  double noise_sigma = 0;              // pixel noise of one frame, image gray levels
  bool dome_normals = false;           // false: every normal is [0, 0, 1]
  Image increment_preview;             // 8-bit: the increment that showed the spots, for --marks
};

LayoutResult find_layout(const LayoutInput& input, const LayoutOptions& options,
                         const Progress& progress = {});

// Draws each element's disk (circle) and position (cross) on the preview: the --marks image.
Image mark_layout(const LayoutResult& result);

// The curves written by `layout` until `fit` replaces them: docs/calibration.md's example curves,
// G scaled to the bit depth.
PiecewiseLinear placeholder_normal_curve(int bit_depth);
PiecewiseLinear placeholder_shear_curve();

// ---------------------------------------------------------------------------------------------
// samples: applied loads against measured values (the fit's input, the measure step's output)

struct Sample {
  std::uint32_t element = 0;
  double fz_n = 0;  // applied normal load
  double G = 0;     // measured integrated gray-scale value
  bool has_x = false;
  double fx_n = 0;   // applied shear load along the image's x (columns)
  double ux_mm = 0;  // measured shear displacement along x
  bool has_y = false;
  double fy_n = 0;
  double uy_mm = 0;
  bool contact = true;  // false: no centroid was measured; the row serves the normal curve only
  std::string frame;    // where it came from (informational)
  std::string where;    // "file:line", for messages
};

// Reads a samples CSV (docs/calibration.md): a header naming the columns, then one row per
// element and load. Throws std::runtime_error naming file, line and column.
std::vector<Sample> parse_samples(const std::string& text, const std::string& source);
std::vector<Sample> read_samples(const std::filesystem::path& path);
std::string format_samples(const std::vector<Sample>& samples);

// One row of a loads CSV: this frame was taken with this load on this element.
struct LoadRow {
  std::string frame;  // as written (relative to the loads file's folder)
  std::uint32_t element = 0;
  double fz_n = 0;
  bool has_x = false;
  double fx_n = 0;
  bool has_y = false;
  double fy_n = 0;
  std::string where;
};

std::vector<LoadRow> parse_loads(const std::string& text, const std::string& source);

// ---------------------------------------------------------------------------------------------
// measure

struct MeasureOptions {
  CentroidEstimator estimator = CentroidEstimator::kGaussian;
  bool reference_spot_check = true;
};

// Measures every frame named in `loads` with the real measurement core (calibration +
// reference = mean of `references`) and returns one sample per row. Each frame is measured on
// its own (contact when G >= contact.on, no hysteresis from the frame before). `load_frame`
// reads a frame by the name in the loads file.
std::vector<Sample> measure_samples(const Calibration& cal, const std::vector<Image>& references,
                                    const std::vector<LoadRow>& loads,
                                    const std::function<Image(const std::string&)>& load_frame,
                                    const MeasureOptions& options, const Progress& progress = {});

// ---------------------------------------------------------------------------------------------
// fit

struct CurveFitOptions {
  int knots = 4;  // knots after 0, placed at quantiles of the measured values
  // Refuse when an element's RMS error exceeds this (N); 0: 5 % of the largest applied load.
  double max_rms_n = 0;
  // Refuse when, at a larger applied load, the mean measured value of an element falls below
  // that at a smaller load by more than this fraction of the element's measured range.
  double monotone_tolerance = 0.02;
  // The curve the fit replaces (the layout's placeholder or an earlier calibration's), if any:
  // only to say which loads to record when the samples cannot show a direction.
  std::optional<PiecewiseLinear> present_curve;
};

struct ElementError {
  std::uint32_t element = 0;
  std::size_t n = 0;
  double rms_n = 0;
  double max_n = 0;  // largest absolute error
};

struct CurveFit {
  PiecewiseLinear curve;
  std::vector<ElementError> per_element;  // by element id
  ElementError all;                       // every sample (element field unused)
  double max_rms_n = 0;                   // the threshold that was applied
  // Empty: the fit is good. Otherwise why it must not be used (an element's RMS error above
  // max_rms_n); the curve and the errors are still there to be reported.
  std::string problem;
};

// F_z = g(G) from (G, fz_N) of every sample.
CurveFit fit_normal_curve(const std::vector<Sample>& samples, const CurveFitOptions& options);
// F = f(u), odd, from (ux_mm, fx_N) and (uy_mm, fy_N) of the samples in contact.
CurveFit fit_shear_curve(const std::vector<Sample>& samples, const CurveFitOptions& options);

// Non-negative least squares: minimises |A x - b| with x >= 0 (Lawson and Hanson), A given as
// rows of `cols` values. Small problems only (cols up to a few dozen).
std::vector<double> nnls(const std::vector<double>& a, std::size_t cols,
                         const std::vector<double>& b);

}  // namespace tactile::calibrate
