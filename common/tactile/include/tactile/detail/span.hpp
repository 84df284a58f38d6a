#pragma once

#include <cstdint>

namespace tactile::detail {

// One image row of an element's disk, as the measurement stores it: columns [x0, x1) of row
// y; ref_offset indexes the disk-pixel arrays (the reference) at (x0, y).
struct Span {
  std::int32_t y;
  std::int32_t x0;
  std::int32_t x1;  // exclusive
  std::uint32_t ref_offset;
};

// An element's disk padded to a rectangle whose rows are a whole number of vector widths
// where the image allows, so that the per-pixel loops run without scalar remainders. Pixels
// of the rectangle outside the disk get thresholds no pixel passes. offset indexes the
// rectangle arrays at (x0, y0); rows are `width` apart.
struct Block {
  std::int32_t x0;
  std::int32_t y0;
  std::int32_t width;
  std::int32_t height;
  std::uint32_t offset;
};

}  // namespace tactile::detail
