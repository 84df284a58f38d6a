#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/detail/span.hpp"
#include "tactile/geometry.hpp"
#include "tactile/image.hpp"
#include "tactile/reading.hpp"

namespace tactile {

namespace detail {
struct KernelSet;
struct BlockData;
struct Moments;
}  // namespace detail

// How the centroid (x_G, y_G) of a spot is estimated. All use the same increments
// dg = g - g_ref over the element's disk S.
enum class CentroidEstimator : std::uint8_t {
  // Eqs. 3 and 4 with w = max(dg, 0): the paper's form, no noise floor.
  kPlain,
  // Eqs. 3 and 4 with w = max(dg - noise_floor, 0): the reference estimator
  // (docs/calibration.md, "Centroid estimators").
  kThresholded,
  // The thresholded centroid, recomputed inside a soft-edged window centred on the first
  // estimate and sized to the spot, so noise far from the spot no longer pulls the estimate
  // toward the disk centre (docs/calibration.md).
  kWindowed,
  // Gaussian-weighted centroid refined by one Newton step on its score, starting from the
  // thresholded centroid (with the weights counted in whole gray levels above the threshold,
  // which is cheaper and as good a start), with the weight's width taken from the spot (from G
  // and the peak increment). For a Gaussian spot in white noise this is the maximum-likelihood
  // position and reaches the Cramer-Rao bound; for any symmetric spot it is unbiased
  // (docs/calibration.md, docs/benchmarks.md). The default: the most accurate estimator for
  // its cost on the benchmark's Pareto front.
  kGaussian,
  // kGaussian with the weight's width found per axis (from each axis's weighted second moment
  // after the first pass), so that an elliptical spot (one wider along an image axis) gets its
  // own matched weight (docs/calibration.md, docs/benchmarks.md).
  kGaussianAxes,
};

// Parses "plain", "thresholded", "windowed", "gaussian" or "gaussian-axes"; nullopt otherwise.
std::optional<CentroidEstimator> parse_estimator(std::string_view name);
// The names parse_estimator accepts, for error messages and --help.
inline constexpr const char* kEstimatorNames =
    "plain, thresholded, windowed, gaussian or gaussian-axes";

const char* to_string(CentroidEstimator e);

struct ExtractorOptions {
  CentroidEstimator estimator = CentroidEstimator::kGaussian;
  // Frames a no-load reference is the mean of.
  int reference_frames = 16;
  // Refuse a reference whose elements show a spot (sum over the inner disk of the excess over
  // the disk's rim ring reaching contact.on).
  bool reference_spot_check = true;
  // A per-frame displacement spans at most this many nominal frame periods; across a longer
  // gap the previous frame is forgotten and displacement restarts at 0.
  std::uint32_t max_gap_frames = 4;
  // kWindowed: the window's half-width is the radius of the above-floor area plus this margin.
  double window_margin_px = 2.0;
  // kGaussian, kGaussianAxes: the weight reaches this many weight-sigmas from the first estimate. 3
  // is as accurate as 3.5 (the cut-off weight is 1 %, the bias it leaves below 0.0005 px) and
  // faster; 2.5 leaves a bias of about 0.003 px (docs/benchmarks.md).
  double gaussian_reach_sigmas = 3.0;
  // Accept frames that cover only part of the sensor (a camera region of interest, see
  // region_of_interest() and ImageView::origin_x/origin_y) as long as they hold every disk.
  // Off: only whole frames of the calibration's size are measured.
  bool accept_regions = false;
  // Use the portable per-pixel loops even where the processor has AVX2 (tests compare the two;
  // the readings agree exactly except for kGaussian's floating-point rounding).
  bool portable_kernels = false;
};

// Position of a frame in the camera's stream. `sequence` counts camera frames (lost frames
// included), so a gap of k means k nominal periods; it never wraps.
struct FrameInfo {
  std::uint64_t sequence = 0;
  std::int64_t timestamp_ns = 0;
};

enum class MeasureStatus : std::uint8_t { kOk, kNoReference, kWrongSize, kWrongFormat };
const char* to_string(MeasureStatus s);

enum class ReferenceStatus : std::uint8_t {
  kCollecting,     // frame accepted; more frames needed
  kComplete,       // the new reference is in use
  kRefusedMotion,  // a frame differs from the running mean: something touches the sensor
  kRefusedLoad,    // the mean shows load against the previous reference
  kRefusedSpot,    // the mean shows a bright spot on an element
  kWrongSize,
  kWrongFormat,
  kNoFrames,  // finish_reference() without any frame
};
const char* to_string(ReferenceStatus s);

struct ReferenceResult {
  ReferenceStatus status = ReferenceStatus::kCollecting;
  int frames = 0;                // frames collected so far in this capture
  std::uint32_t element_id = 0;  // the element that caused a refusal
  double value = 0;              // its excess, in G units (gray levels)
};

// The measurement core: image -> per-element readings (docs/calibration.md, "The measurement
// of one frame"). Construction validates the calibration and allocates everything; measure()
// allocates nothing, never throws and never yields NaN or infinity.
class Extractor {
 public:
  explicit Extractor(Calibration cal, ExtractorOptions options = {});

  const Calibration& calibration() const { return cal_; }
  const ExtractorOptions& options() const { return opt_; }

  // --- no-load reference g_ref -------------------------------------------------------------
  // Starts a new capture. The previous reference (if any) stays in use, and is the baseline of
  // the load check, until the new one completes.
  void begin_reference();
  // Adds one no-load frame; the capture completes by itself after options().reference_frames.
  ReferenceResult add_reference_frame(const ImageView& frame);
  // Completes a capture with the frames collected so far (at least one).
  ReferenceResult finish_reference();
  bool has_reference() const { return has_reference_; }
  // The reference mean rounded to the sensor's gray levels, whole frame (to save and reload).
  const Image& reference_image() const { return reference_image_; }

  // --- per frame -----------------------------------------------------------------------------
  MeasureStatus measure(const ImageView& frame, FrameInfo info) noexcept;
  std::span<const ElementReading> readings() const { return readings_; }
  // The next frame is treated as having no predecessor (no displacement).
  void forget_previous() noexcept;

 private:
  using Span = detail::Span;
  struct ElementLayout {
    std::uint32_t span_begin;
    std::uint32_t span_end;
    std::int32_t origin_x;  // left column of the disk's bounding box
    std::int32_t origin_y;  // top row
  };
  struct ElementState {
    bool contact = false;
    double x_px = 0;
    double y_px = 0;
  };

  // The arrays detail::BlockData points into, one value per block pixel, built from the
  // reference by build_block_tables(): the G threshold and the reference (kPlain's centroid
  // threshold, kGaussian's baseline) in Q8, and the narrow forms of both that the kernels read
  // (src/kernels.hpp). Parallel arrays, not one struct per pixel: the kernels load each of them
  // a vector at a time.
  struct BlockTables {
    std::vector<std::int32_t> thr;
    std::vector<std::int32_t> ref;
    std::vector<std::uint16_t> thr16;
    std::vector<std::uint16_t> ref16;
    std::vector<std::uint8_t> thr_hi8;
    std::vector<std::uint8_t> thr_lo;
    std::vector<std::uint16_t> thr_hi16;
    std::vector<std::uint8_t> ref_hi8;
    std::vector<std::uint8_t> ref_lo;
  };

  bool geometry_matches(const ImageView& f) const;
  template <typename Pixel>
  bool windowed_pass(std::size_t element, const ImageView& f, double& x, double& y,
                     double half_width) const noexcept;
  template <typename Pixel>
  bool gaussian_pass(std::size_t element, const ImageView& f, double& x, double& y, Vec2& sigma,
                     bool per_axis) noexcept;
  template <typename Pixel>
  void gaussian_refine(std::size_t element, const ImageView& f, const detail::Moments& m, double g,
                       bool per_axis, Vec2& p) noexcept;
  template <typename Pixel>
  Vec2 centroid(std::size_t element, const ImageView& f, const detail::Moments& m,
                double g) noexcept;
  void record_contact(std::size_t element, Vec2 p, double g, std::uint32_t gap) noexcept;
  template <typename Pixel>
  void measure_all(const ImageView& f, std::uint32_t gap) noexcept;
  void build_block_tables();
  void set_block_pixel(std::size_t at, std::int32_t ref_q);
  detail::BlockData block_data() const noexcept;
  ReferenceResult complete_reference();
  ReferenceResult refuse(ReferenceStatus s, std::uint32_t id, double value);

  Calibration cal_;
  ExtractorOptions opt_;
  std::int32_t floor_q_ = 0;
  std::vector<Span> spans_;
  std::vector<ElementLayout> layout_;
  // The reference mean in Q8 (x256), disk pixels only.
  std::vector<std::int32_t> ref_q_;
  // Each element's disk padded to a block (detail::Block), and the tables over the blocks.
  std::vector<detail::Block> blocks_;
  BlockTables tables_;
  const detail::KernelSet* kernels_ = nullptr;
  bool has_reference_ = false;
  Region disks_;  // the smallest region holding every disk pixel

  Image reference_image_;

  // Reference capture (not a per-frame path): per-pixel sums over the whole frame.
  std::vector<std::uint32_t> capture_sum_;
  int capture_frames_ = 0;

  // Scratch for kGaussian's separable weights, sized at construction to the largest disk.
  std::vector<float> wx_, wxu_, wxu2_, wy_;

  std::vector<ElementState> state_;
  std::vector<ElementReading> readings_;
  bool has_previous_ = false;
  std::uint64_t previous_sequence_ = 0;
};

}  // namespace tactile
