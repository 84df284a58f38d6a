#include "test_images.hpp"

#include <fmt/core.h>

namespace tactile::camera::testing {

std::uint32_t pattern_value(PixelFormat format, int x, int y, std::uint64_t k, std::uint32_t salt) {
  const auto ux = static_cast<std::uint32_t>(x);
  const auto uy = static_cast<std::uint32_t>(y);
  const auto uk = static_cast<std::uint32_t>(k);
  std::uint32_t h = ux * 0x9E3779B1U ^ (uy * 0x85EBCA77U + uk * 0xC2B2AE3DU + salt);
  h ^= h >> 15;
  h *= 0x2C1B3C6DU;
  h ^= h >> 12;
  return format == PixelFormat::kMono8 ? (h & 0xFFU) : (h & 0xFFFFU);
}

void render_pattern(Image& image, std::uint64_t k, std::uint32_t salt) {
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      image.set(x, y, pattern_value(image.format(), x, y, k, salt));
    }
  }
}

std::optional<std::uint64_t> TimestampCode::decode(std::int64_t timestamp_ns) const {
  const std::int64_t offset = timestamp_ns - base_ns;
  if (offset < 0 || offset % step_ns != 0) return std::nullopt;
  return static_cast<std::uint64_t>(offset / step_ns);
}

std::string compare_to_pattern(const ImageView& view, std::uint64_t k, std::uint32_t salt) {
  if (view.data == nullptr) return "no pixels";
  for (int y = 0; y < view.height; ++y) {
    for (int x = 0; x < view.width; ++x) {
      // The pattern of the sensor's pixel: a region of interest's view starts at its origin.
      const int sx = x + view.origin_x;
      const int sy = y + view.origin_y;
      const std::uint32_t want = pattern_value(view.format, sx, sy, k, salt);
      const std::uint32_t got = view.at(x, y);
      if (got != want) {
        return fmt::format("frame {}: pixel ({}, {}) of the sensor is {}, expected {}", k, sx, sy,
                           got, want);
      }
    }
  }
  return {};
}

}  // namespace tactile::camera::testing
