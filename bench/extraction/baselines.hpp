#pragma once

// The two references every estimator is measured against in the same run (docs/benchmarks.md):
// what a typical user would write with OpenCV, and the cost of only reading the pixels.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/image.hpp"

namespace tactile::bench {

// The OpenCV baseline: the reference is the float mean of the no-load frames; each frame is
// converted to float, cv::absdiff against the reference, cv::threshold (THRESH_TOZERO at the
// noise floor), and cv::moments on each element's bounding square; contact when m00 reaches
// contact.on. All in float, whole frame, as the OpenCV documentation suggests.
class OpenCvBaseline {
 public:
  struct Result {
    bool contact = false;
    double G = 0;
    double x_px = 0;
    double y_px = 0;
  };

  explicit OpenCvBaseline(const Calibration& cal);
  ~OpenCvBaseline();
  OpenCvBaseline(const OpenCvBaseline&) = delete;
  OpenCvBaseline& operator=(const OpenCvBaseline&) = delete;

  void set_reference(std::span<const Image> frames);
  void measure(const ImageView& frame);
  std::span<const Result> results() const { return results_; }

 private:
  struct Mats;
  const Calibration& cal_;
  std::unique_ptr<Mats> m_;
  std::vector<Result> results_;
};

// The floor: one pass over the pixels of every element's disk that only sums them (the same
// pixels the measurement reads, in the same order, compiled the same way).
class PixelSumFloor {
 public:
  explicit PixelSumFloor(const Calibration& cal);
  void measure(const ImageView& frame) noexcept;
  std::span<const std::uint64_t> sums() const { return sums_; }

 private:
  std::vector<DiskRow> rows_;
  std::vector<std::uint32_t> row_end_;  // per element, one past its last row in rows_
  std::vector<std::uint64_t> sums_;
};

}  // namespace tactile::bench
