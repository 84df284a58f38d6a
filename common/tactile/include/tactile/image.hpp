#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace tactile {

// Monochrome pixel formats the measurement accepts (GenICam Mono8 and Mono16).
enum class PixelFormat : std::uint8_t { kMono8, kMono16 };

inline int bit_depth(PixelFormat f) {
  return f == PixelFormat::kMono8 ? 8 : 16;
}
inline std::size_t bytes_per_pixel(PixelFormat f) {
  return f == PixelFormat::kMono8 ? 1 : 2;
}

// A borrowed view of one camera frame. Mono16 pixels are host-endian; x is the column index,
// y the row index, and row y starts at data + y * stride_bytes.
//
// A camera set to a region of interest (region_of_interest() in calibration.hpp) delivers part
// of the sensor's image: origin_x and origin_y say where the view's pixel (0, 0) lies on the
// sensor. row() and at() take the view's own coordinates.
struct ImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  std::size_t stride_bytes = 0;
  PixelFormat format = PixelFormat::kMono8;
  int origin_x = 0;
  int origin_y = 0;

  template <typename Pixel>
  const Pixel* row(int y) const {
    return reinterpret_cast<const Pixel*>(data + static_cast<std::size_t>(y) * stride_bytes);
  }
  // Pixel value widened to 32 bits; no bounds check (use inside loops that already clipped).
  std::uint32_t at(int x, int y) const {
    return format == PixelFormat::kMono8 ? row<std::uint8_t>(y)[x] : row<std::uint16_t>(y)[x];
  }
};

// An owned frame (tests, the rig's renderer, files). Not used in per-frame paths except as a
// buffer allocated once and reused.
class Image {
 public:
  Image() = default;
  Image(int width, int height, PixelFormat format)
      : width_(width),
        height_(height),
        format_(format),
        bytes_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
               bytes_per_pixel(format)) {}

  int width() const { return width_; }
  int height() const { return height_; }
  PixelFormat format() const { return format_; }
  std::size_t stride_bytes() const {
    return static_cast<std::size_t>(width_) * bytes_per_pixel(format_);
  }
  std::span<std::uint8_t> bytes() { return bytes_; }
  std::span<const std::uint8_t> bytes() const { return bytes_; }

  ImageView view() const { return {bytes_.data(), width_, height_, stride_bytes(), format_}; }

  void set(int x, int y, std::uint32_t v) {
    const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                          static_cast<std::size_t>(x);
    if (format_ == PixelFormat::kMono8) {
      bytes_[i] = static_cast<std::uint8_t>(v);
    } else {
      reinterpret_cast<std::uint16_t*>(bytes_.data())[i] = static_cast<std::uint16_t>(v);
    }
  }
  std::uint32_t get(int x, int y) const { return view().at(x, y); }

 private:
  int width_ = 0;
  int height_ = 0;
  PixelFormat format_ = PixelFormat::kMono8;
  std::vector<std::uint8_t> bytes_;
};

}  // namespace tactile
