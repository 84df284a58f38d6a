#include "baselines.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tactile/detail/multiversion.hpp"

namespace tactile::bench {

struct OpenCvBaseline::Mats {
  cv::Mat ref;    // CV_32F
  cv::Mat frame;  // CV_32F
  cv::Mat diff;
  std::vector<cv::Rect> boxes;
};

OpenCvBaseline::OpenCvBaseline(const Calibration& cal)
    : cal_(cal), m_(std::make_unique<Mats>()), results_(cal.elements.size()) {
  for (const ElementCalibration& e : cal.elements) {
    const int x0 = static_cast<int>(std::ceil(e.center_px.x - e.radius_px));
    const int y0 = static_cast<int>(std::ceil(e.center_px.y - e.radius_px));
    const int x1 = static_cast<int>(std::floor(e.center_px.x + e.radius_px));
    const int y1 = static_cast<int>(std::floor(e.center_px.y + e.radius_px));
    m_->boxes.emplace_back(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  }
}

OpenCvBaseline::~OpenCvBaseline() = default;

namespace {

cv::Mat wrap(const ImageView& v) {
  const int type = v.format == PixelFormat::kMono8 ? CV_8U : CV_16U;
  return {v.height, v.width, type, const_cast<std::uint8_t*>(v.data), v.stride_bytes};
}

}  // namespace

void OpenCvBaseline::set_reference(std::span<const Image> frames) {
  cv::Mat sum = cv::Mat::zeros(cal_.height, cal_.width, CV_32F);
  for (const Image& f : frames)
    cv::accumulate(wrap(f.view()), sum);
  m_->ref = sum / static_cast<double>(frames.size());
}

void OpenCvBaseline::measure(const ImageView& frame) {
  wrap(frame).convertTo(m_->frame, CV_32F);
  cv::absdiff(m_->frame, m_->ref, m_->diff);
  cv::threshold(m_->diff, m_->diff, cal_.noise_floor, 0, cv::THRESH_TOZERO);
  for (std::size_t i = 0; i < results_.size(); ++i) {
    const cv::Rect& b = m_->boxes[i];
    const cv::Moments mo = cv::moments(m_->diff(b));
    Result& r = results_[i];
    r.G = mo.m00;
    r.contact = mo.m00 >= cal_.contact_on;
    r.x_px = r.contact ? b.x + mo.m10 / mo.m00 : 0;
    r.y_px = r.contact ? b.y + mo.m01 / mo.m00 : 0;
  }
}

PixelSumFloor::PixelSumFloor(const Calibration& cal) {
  for (const ElementCalibration& e : cal.elements) {
    for (const DiskRow& r : disk_rows(e.center_px, e.radius_px))
      rows_.push_back(r);
    row_end_.push_back(static_cast<std::uint32_t>(rows_.size()));
  }
  sums_.assign(cal.elements.size(), 0);
}

namespace {

template <typename Pixel>
[[gnu::always_inline]] inline void sum_rows(const DiskRow* rows, const std::uint32_t* ends,
                                            std::size_t elements, const ImageView& f,
                                            std::uint64_t* sums) noexcept {
  std::uint32_t r = 0;
  for (std::size_t e = 0; e < elements; ++e) {
    std::uint64_t total = 0;
    for (; r < ends[e]; ++r) {
      const DiskRow& row = rows[r];
      const Pixel* p = f.row<Pixel>(row.y - f.origin_y) + (row.x0 - f.origin_x);
      std::uint32_t s = 0;
      for (int k = 0; k < row.x1 - row.x0; ++k)
        s += p[k];
      total += s;
    }
    sums[e] = total;
  }
}

// Cloned as the core's kernels are, so that the floor gets every advantage the measurement gets.
TACTILE_CLONES
void sum_u8(const DiskRow* rows, const std::uint32_t* ends, std::size_t elements,
            const ImageView& f, std::uint64_t* sums) noexcept {
  sum_rows<std::uint8_t>(rows, ends, elements, f, sums);
}

TACTILE_CLONES
void sum_u16(const DiskRow* rows, const std::uint32_t* ends, std::size_t elements,
             const ImageView& f, std::uint64_t* sums) noexcept {
  sum_rows<std::uint16_t>(rows, ends, elements, f, sums);
}

}  // namespace

void PixelSumFloor::measure(const ImageView& frame) noexcept {
  if (frame.format == PixelFormat::kMono8) {
    sum_u8(rows_.data(), row_end_.data(), sums_.size(), frame, sums_.data());
  } else {
    sum_u16(rows_.data(), row_end_.data(), sums_.size(), frame, sums_.data());
  }
}

}  // namespace tactile::bench
