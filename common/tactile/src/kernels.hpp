#pragma once

// The per-pixel loops of the measurement. Two implementations of each: portable C++ (plain
// loops and the compiler's generic vector types, compiled for any x86-64 and cloned for
// x86-64-v3), and AVX2 intrinsics for 8- and 16-bit pixels (x86-64 only, chosen at run time when
// the processor has AVX2 and FMA). The integer kernels of both give identical results (tests
// compare them); the floating-point one differs only in rounding. Every function here is noexcept,
// allocates nothing and reads only the block it is given.
#include <bit>
#include <cstddef>
#include <cstdint>

#include "tactile/detail/span.hpp"

namespace tactile::detail {

// A frame as the kernels read it: sensor pixel (x, y) lives at
// data + (y - origin_y) * stride + (x - origin_x) * sizeof(Pixel).
struct FrameRef {
  const std::uint8_t* data = nullptr;
  std::size_t stride = 0;
  int origin_x = 0;
  int origin_y = 0;

  template <typename Pixel>
  const Pixel* pixel(int x, int y) const noexcept {
    return reinterpret_cast<const Pixel*>(data + static_cast<std::size_t>(y - origin_y) * stride) +
           (x - origin_x);
  }
};

// Asks the processor to start loading the frame rows of a block (the first and the last byte of
// each row: at most two cache lines of a block up to 64 bytes wide). A hint only: it reads
// nothing and cannot fault. The measurement issues it for the next element while it works on the
// Gaussian step of the current one, which reads little memory; issued before a pass over pixels
// it competes with that pass's own loads and costs time (docs/findings.md, extraction 2).
template <typename Pixel>
inline void prefetch_block(const Block& b, const FrameRef& f) noexcept {
  const auto* row = reinterpret_cast<const std::uint8_t*>(f.pixel<Pixel>(b.x0, b.y0));
  const std::size_t last = static_cast<std::size_t>(b.width) * sizeof(Pixel) - 1;
  for (int r = 0; r < b.height; ++r, row += f.stride) {
    __builtin_prefetch(row);
    __builtin_prefetch(row + last);
  }
}

// Reference value of block pixels outside the disk: larger than any 256 p, so such pixels never
// weigh anything, and recognisable as outside.
inline constexpr std::int32_t kOutsideDisk = 1 << 30;

// Per-pixel arrays of the block layout (all indexed with Block::offset, rows Block::width
// apart), derived from the reference. A Q8 threshold t is also kept split as t = 256 hi + lo
// (0 <= lo < 256, hi clamped to the largest level): then the weight of a pixel p is
//   max(256 p - t, 0) = 256 s - (s > 0 ? lo : 0),   s = max(p - hi, 0),
// which narrow integers compute exactly.
struct BlockData {
  const std::int32_t* thr = nullptr;        // G threshold: reference + noise floor, Q8
  const std::int32_t* ref = nullptr;        // reference, Q8; kOutsideDisk outside the disk
  const std::uint16_t* thr16 = nullptr;     // 8-bit sensors: thr clamped to 65535
  const std::uint16_t* ref16 = nullptr;     // 8-bit sensors: ref clamped to 65535
  const std::uint8_t* thr_hi8 = nullptr;    // 8-bit sensors: thr split
  const std::uint8_t* thr_lo = nullptr;     // (both depths)
  const std::uint16_t* thr_hi16 = nullptr;  // 16-bit sensors: thr split
  const std::uint8_t* ref_hi8 = nullptr;    // 8-bit sensors: ref split (kPlain's centroid weights)
  const std::uint8_t* ref_lo = nullptr;
};

// Exact G of one element: G_q8 = 256 * s_sum - lo_sum.
struct GSum {
  std::uint64_t s_sum = 0;
  std::uint64_t lo_sum = 0;
  std::int64_t g_q8() const { return static_cast<std::int64_t>(256 * s_sum - lo_sum); }
};

// Weighted moments of one element over its block, exact, in Q8.
struct Moments {
  std::int64_t g = 0;      // sum of the G weights
  std::int64_t c0 = 0;     // sum of the centroid weights
  std::int64_t cx = 0;     // sum of centroid weight * (x - block x0)
  std::int64_t cy = 0;     // sum of centroid weight * (y - block y0)
  std::int64_t above = 0;  // pixels with a positive centroid weight (kThresholdedCount only)
  std::int32_t peak = 0;   // largest s of the G weights: whole gray levels above the threshold
};

enum class MomentKind : std::uint8_t {
  kThresholded,       // centroid weights = G weights
  kThresholdedCount,  // the same, and the count of pixels above the threshold
  kPlain,             // centroid weights max(256 p - ref, 0): no noise floor
  // Centroid weights s = ceil(w / 256), whole gray levels above the threshold: nearly the
  // thresholded centroid, for a start point, and cheaper (c0, cx, cy in gray levels, not Q8).
  kStart,
};

// Sums of the Gaussian-weighted score of one element over the block rows [row_lo, row_hi]
// (image rows) and the block columns that meet [col_lo, col_hi], with the raw increment
// d = 256 p - ref of the disk's pixels (negative values included): with u = x - cx, v = y - cy
// and separable weights W = wx(x) wy(y), wx(x) = exp(-a_x u^2), wy(y) = exp(-a_y v^2),
//   s0 = sum d W, s1x = sum d W u, s2x = sum d W u^2, s1y = sum d W v, s2y = sum d W v^2.
// The kernels compute the weights themselves, in the scratch arrays as far as they need them:
// wx, wxu and wxu2 one value per block column, with kGaussPad writable columns either side (at
// least block width + 2 kGaussPad floats from wx - kGaussPad); wy one per window row plus
// kGaussPad. The window keeps -a_x u^2 >= -72 and -a_y v^2 >= -72 (reach at most 12 sigmas).
inline constexpr int kGaussPad = 16;
struct GaussSums {
  double s0 = 0, s1x = 0, s2x = 0, s1y = 0, s2y = 0;
};
struct GaussWindow {
  int row_lo;
  int row_hi;
  int col_lo;
  int col_hi;
  double cx;
  double cy;
  double a_x;  // 1 / (2 sigma_x^2) of the weight along the columns
  double a_y;  // along the rows
  float* wx;
  float* wxu;
  float* wxu2;
  float* wy;
  // Every pixel of the window lies in the disk (kernels may then skip the outside test).
  bool inside_disk = false;
};

// exp(x) for x in [-87, 0], to about 3e-7 relative, without branches or library calls, so that
// loops over it vectorise: x = n ln 2 + r with |r| <= ln 2 / 2, a degree-6 polynomial for
// exp(r), 2^n put into the exponent bits. The AVX2 kernels compute the same polynomial eight
// lanes at a time.
inline float exp_nonpositive(float x) noexcept {
  const float t = x * 1.44269504F;                                // x / ln 2, in [-125.6, 0]
  const auto n = static_cast<float>(static_cast<int>(t - 0.5F));  // nearest integer, t <= 0
  const float r = (x - n * 0.693145752F) - n * 1.42860677e-6F;    // ln 2 in two parts
  float p = 1.0F / 720;
  p = p * r + 1.0F / 120;
  p = p * r + 1.0F / 24;
  p = p * r + 1.0F / 6;
  p = p * r + 0.5F;
  p = p * r + 1.0F;
  p = p * r + 1.0F;
  const auto scale =
      std::bit_cast<float>(static_cast<std::uint32_t>(static_cast<int>(n) + 127) << 23);
  return p * scale;
}

// One implementation of every kernel.
struct KernelSet {
  const char* name;
  GSum (*exact_g_u8)(const Block&, const FrameRef&, const BlockData&) noexcept;
  GSum (*exact_g_u16)(const Block&, const FrameRef&, const BlockData&) noexcept;
  Moments (*moments_u8)(const Block&, const FrameRef&, const BlockData&, MomentKind) noexcept;
  Moments (*moments_u16)(const Block&, const FrameRef&, const BlockData&, MomentKind) noexcept;
  GaussSums (*gauss_u8)(const Block&, const FrameRef&, const BlockData&,
                        const GaussWindow&) noexcept;
  GaussSums (*gauss_u16)(const Block&, const FrameRef&, const BlockData&,
                         const GaussWindow&) noexcept;
};

// The portable implementation: always there.
const KernelSet& portable_kernels() noexcept;
// The AVX2 implementation (blocks it does not take, such as odd widths, go to the portable
// kernels), or nullptr where the build or the processor does not have AVX2 and FMA.
const KernelSet* avx2_kernels() noexcept;
// The fastest implementation this processor runs.
const KernelSet& best_kernels() noexcept;

}  // namespace tactile::detail
