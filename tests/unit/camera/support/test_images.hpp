#pragma once

// Deterministic test frames: the image of frame k of a camera, and the timestamp it is
// published with, so a receiver can tell from the timestamp alone which pixels it must hold.
#include <cstdint>
#include <optional>
#include <string>

#include "tactile/image.hpp"

namespace tactile::camera::testing {

// Every pixel depends on x, y, the frame index k and a per-camera salt; Mono16 values use both
// bytes, so a byte-order or offset fault changes them.
std::uint32_t pattern_value(PixelFormat format, int x, int y, std::uint64_t k, std::uint32_t salt);
void render_pattern(Image& image, std::uint64_t k, std::uint32_t salt);

// Timestamps of published frames: base + k * step (base and step chosen by the test).
struct TimestampCode {
  std::int64_t base_ns = 1'700'000'000'000'000'000;
  std::int64_t step_ns = 1000;
  std::int64_t encode(std::uint64_t k) const {
    return base_ns + static_cast<std::int64_t>(k) * step_ns;
  }
  std::optional<std::uint64_t> decode(std::int64_t timestamp_ns) const;
};

// Empty when `view` equals the pattern of frame k; otherwise where it first differs.
std::string compare_to_pattern(const ImageView& view, std::uint64_t k, std::uint32_t salt);

}  // namespace tactile::camera::testing
