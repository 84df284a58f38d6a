#include "kernels.hpp"

#include <algorithm>
#include <cstring>

#include "tactile/detail/multiversion.hpp"

// The portable kernels. Each exported function is cloned for x86-64-v3 (AVX2, FMA) beside the
// baseline build; the dynamic loader picks the clone once (ifunc). The fast paths use the
// compiler's generic vector types (GCC and Clang), which it lowers to whatever the clone's
// instruction set has: 16-byte SSE2 registers in the baseline, AVX2 in the other clone, other
// SIMD on other targets. Blocks that do not fit a fast path (16-bit pixels in the integer
// passes, odd widths, huge disks) go through plain loops. Builds that define
// TACTILE_NO_MULTIVERSION get the baseline only (tactile/detail/multiversion.hpp).

namespace tactile::detail {
namespace {

using u8x16 = std::uint8_t __attribute__((vector_size(16)));
using u16x16 = std::uint16_t __attribute__((vector_size(32)));
using i32x8 = std::int32_t __attribute__((vector_size(32)));
using u32x8 = std::uint32_t __attribute__((vector_size(32)));
using f32x8 = float __attribute__((vector_size(32)));

std::size_t row_at(const Block& b, int r) {
  return b.offset + static_cast<std::size_t>(r) * static_cast<std::size_t>(b.width);
}

// --- exact G -----------------------------------------------------------------------------------

template <typename Pixel>
[[gnu::always_inline]] inline GSum exact_g_plain(const Block& b, const FrameRef& f, const Pixel* hi,
                                                 const std::uint8_t* lo) noexcept {
  GSum out;
  for (int r = 0; r < b.height; ++r) {
    const Pixel* p = f.pixel<Pixel>(b.x0, b.y0 + r);
    const Pixel* h = hi + row_at(b, r);
    const std::uint8_t* l = lo + row_at(b, r);
    // A row holds at most 2080 pixels: 32-bit sums of 16-bit values cannot overflow.
    std::uint32_t ss = 0;
    std::uint32_t ls = 0;
    for (int k = 0; k < b.width; ++k) {
      const Pixel hk = h[k];
      const auto s = static_cast<Pixel>(std::max(p[k], hk) - hk);
      const std::uint32_t lk = l[k];
      ss += s;
      ls += lk & (0U - static_cast<std::uint32_t>(s != 0));
    }
    out.s_sum += ss;
    out.lo_sum += ls;
  }
  return out;
}

// 8-bit pixels, block width a multiple of 16: 16 pixels at a time in 8-bit lanes, summed in
// 16-bit lanes (at most 255 per pixel, flushed every 256 vectors).
[[gnu::always_inline]] inline GSum exact_g_vec8(const Block& b, const FrameRef& f,
                                                const std::uint8_t* hi,
                                                const std::uint8_t* lo) noexcept {
  GSum out;
  u16x16 acc_s = {};
  u16x16 acc_l = {};
  int since_flush = 0;
  const auto flush = [&] {
    for (int j = 0; j < 16; ++j) {
      out.s_sum += acc_s[j];
      out.lo_sum += acc_l[j];
    }
    acc_s = u16x16{};
    acc_l = u16x16{};
    since_flush = 0;
  };
  for (int r = 0; r < b.height; ++r) {
    const std::uint8_t* p = f.pixel<std::uint8_t>(b.x0, b.y0 + r);
    const std::uint8_t* h = hi + row_at(b, r);
    const std::uint8_t* l = lo + row_at(b, r);
    for (int g = 0; g < b.width; g += 16) {
      u8x16 pv;
      u8x16 hv;
      u8x16 lv;
      std::memcpy(&pv, p + g, sizeof pv);
      std::memcpy(&hv, h + g, sizeof hv);
      std::memcpy(&lv, l + g, sizeof lv);
      const u8x16 s = (pv > hv ? pv : hv) - hv;
      const u8x16 lm = lv & reinterpret_cast<u8x16>(s != 0);
      acc_s += __builtin_convertvector(s, u16x16);
      acc_l += __builtin_convertvector(lm, u16x16);
      if (++since_flush == 256) flush();
    }
  }
  flush();
  return out;
}

// --- moments -----------------------------------------------------------------------------------

// Rows are cut into chunks short enough that 32-bit sums of w and of w * (column in chunk)
// cannot overflow (w < 2^16 for 8-bit pixels, < 2^24 for 16-bit ones); chunk totals go into
// 64-bit sums.
template <typename Pixel>
constexpr int kChunk = sizeof(Pixel) == 1 ? 64 : 16;

template <typename Pixel, bool kSeparateCentroid, bool kCountAbove, bool kWholeLevels = false>
[[gnu::always_inline]] inline Moments moments_plain(const Block& b, const FrameRef& f,
                                                    const std::int32_t* thr,
                                                    const std::int32_t* thr_c) noexcept {
  Moments m;
  for (int r = 0; r < b.height; ++r) {
    const Pixel* p = f.pixel<Pixel>(b.x0, b.y0 + r);
    const std::int32_t* t = thr + row_at(b, r);
    const std::int32_t* tc = kSeparateCentroid ? thr_c + row_at(b, r) : t;
    std::int64_t row_c = 0;
    for (int c = 0; c < b.width; c += kChunk<Pixel>) {
      const int len = std::min(kChunk<Pixel>, b.width - c);
      std::uint32_t sg = 0;
      std::uint32_t sc = 0;
      std::uint32_t scx = 0;
      std::uint32_t sa = 0;
      std::int32_t peak = 0;
      for (int k = 0; k < len; ++k) {
        const std::int32_t v = static_cast<std::int32_t>(p[c + k]) << 8;
        const std::int32_t w = std::max(v - t[c + k], 0);
        sg += static_cast<std::uint32_t>(w);
        peak = std::max(peak, w);
        const std::int32_t wc = kSeparateCentroid ? std::max(v - tc[c + k], 0)
                                : kWholeLevels    ? (w + 255) >> 8
                                                  : w;
        if constexpr (kSeparateCentroid || kWholeLevels) sc += static_cast<std::uint32_t>(wc);
        scx += static_cast<std::uint32_t>(wc) * static_cast<std::uint32_t>(k);
        if constexpr (kCountAbove) sa += wc > 0 ? 1U : 0U;
      }
      const std::uint32_t chunk_c = kSeparateCentroid || kWholeLevels ? sc : sg;
      m.g += sg;
      row_c += chunk_c;
      m.cx += static_cast<std::int64_t>(scx) + static_cast<std::int64_t>(chunk_c) * c;
      m.peak = std::max(m.peak, (peak + 255) >> 8);  // s = ceil(w / 256)
      m.above += sa;
    }
    m.c0 += row_c;
    m.cy += row_c * r;
  }
  return m;
}

// Widest block the vector moments take: lane sums of w * column stay below 2^32 for at least
// one row (16 pixels per lane x 65280 x 255 < 2^32).
constexpr int kMaxVectorWidth = 256;

// The low and high halves of a 16-lane vector, widened to 32 bits.
#define TACTILE_LOW_HALF(v) \
  __builtin_convertvector(__builtin_shufflevector(v, v, 0, 1, 2, 3, 4, 5, 6, 7), u32x8)
#define TACTILE_HIGH_HALF(v) \
  __builtin_convertvector(__builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15), u32x8)

// 8-bit pixels, block width a multiple of 16 up to kMaxVectorWidth: 16 pixels at a time. The
// weight max(256 p - t, 0) is exact in 16-bit lanes (256 p <= 65280; thresholds are stored
// clamped to 65535, which no pixel passes). Sums go to 32-bit lanes, flushed to 64 bits every
// `batch` rows, chosen so that none can overflow; row indices inside a batch are local and the
// batch start is added at the flush.
template <bool kSeparateCentroid, bool kCountAbove, bool kWholeLevels = false>
[[gnu::always_inline]] inline Moments moments_vec8(const Block& b, const FrameRef& f,
                                                   const std::uint16_t* thr,
                                                   const std::uint16_t* thr_c) noexcept {
  Moments m;
  const std::uint64_t per_lane_row = static_cast<std::uint64_t>(b.width / 16) * 65280U;
  // Bounds per lane after n rows: g <= n a, cx <= n a (W - 1), cy <= n^2 a / 2 (a = per row);
  // the pixel count per 16-bit lane <= n W / 16.
  int batch = 1;
  while (batch < b.height) {
    const std::uint64_t n = static_cast<std::uint64_t>(batch) * 2;
    const std::uint64_t worst =
        n * per_lane_row * std::max<std::uint64_t>(static_cast<std::uint64_t>(b.width - 1), n / 2);
    if (worst >= (std::uint64_t{1} << 32) || n * static_cast<std::uint64_t>(b.width) / 16 > 65535)
      break;
    batch *= 2;
  }
  const u32x8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  u16x16 peak = {};
  for (int r0 = 0; r0 < b.height; r0 += batch) {
    const int r1 = std::min(b.height, r0 + batch);
    u32x8 acc_g = {};
    u32x8 acc_c = {};
    u32x8 acc_x = {};
    u32x8 acc_y = {};
    u16x16 acc_a = {};
    for (int r = r0; r < r1; ++r) {
      const std::uint8_t* p = f.pixel<std::uint8_t>(b.x0, b.y0 + r);
      const std::uint16_t* t = thr + row_at(b, r);
      const std::uint16_t* tc = kSeparateCentroid ? thr_c + row_at(b, r) : t;
      u32x8 row_c = {};
      for (int g = 0; g < b.width; g += 16) {
        u8x16 pv;
        u16x16 tv;
        std::memcpy(&pv, p + g, sizeof pv);
        std::memcpy(&tv, t + g, sizeof tv);
        const u16x16 v = __builtin_convertvector(pv, u16x16) << 8;
        const u16x16 w = (v > tv ? v : tv) - tv;
        peak = peak > w ? peak : w;
        u16x16 wc = w;
        if constexpr (kWholeLevels) {
          wc = (w + 255) >> 8;
          acc_g += TACTILE_LOW_HALF(w) + TACTILE_HIGH_HALF(w);
        }
        if constexpr (kSeparateCentroid) {
          u16x16 tcv;
          std::memcpy(&tcv, tc + g, sizeof tcv);
          wc = (v > tcv ? v : tcv) - tcv;
          const u32x8 g0 = TACTILE_LOW_HALF(w);
          const u32x8 g1 = TACTILE_HIGH_HALF(w);
          acc_g += g0 + g1;
        }
        if constexpr (kCountAbove) acc_a -= reinterpret_cast<u16x16>(wc != 0);
        const u32x8 c0 = TACTILE_LOW_HALF(wc);
        const u32x8 c1 = TACTILE_HIGH_HALF(wc);
        const u32x8 col = lane + static_cast<std::uint32_t>(g);
        row_c += c0 + c1;
        acc_x += c0 * col + c1 * (col + 8U);
      }
      if constexpr (!kSeparateCentroid && !kWholeLevels) acc_g += row_c;
      acc_c += row_c;
      acc_y += row_c * static_cast<std::uint32_t>(r - r0);
    }
    std::uint64_t sum_c = 0;
    for (int j = 0; j < 8; ++j) {
      m.g += acc_g[j];
      sum_c += acc_c[j];
      m.cx += acc_x[j];
      m.cy += acc_y[j];
    }
    for (int j = 0; j < 16; ++j)
      m.above += acc_a[j];
    m.c0 += static_cast<std::int64_t>(sum_c);
    m.cy += static_cast<std::int64_t>(sum_c) * r0;
  }
  for (int j = 0; j < 16; ++j)
    m.peak = std::max<std::int32_t>(m.peak, (peak[j] + 255) >> 8);  // s = ceil(w / 256)
  return m;
}

template <typename Pixel>
[[gnu::always_inline]] inline Moments moments_dispatch(const Block& b, const FrameRef& f,
                                                       const BlockData& d,
                                                       MomentKind kind) noexcept {
  if constexpr (sizeof(Pixel) == 1) {
    if (b.width % 16 == 0 && b.width <= kMaxVectorWidth) {
      switch (kind) {
        case MomentKind::kPlain:
          return moments_vec8<true, false>(b, f, d.thr16, d.ref16);
        case MomentKind::kThresholdedCount:
          return moments_vec8<false, true>(b, f, d.thr16, nullptr);
        case MomentKind::kStart:
          return moments_vec8<false, false, true>(b, f, d.thr16, nullptr);
        case MomentKind::kThresholded:
          break;
      }
      return moments_vec8<false, false>(b, f, d.thr16, nullptr);
    }
  }
  switch (kind) {
    case MomentKind::kPlain:
      return moments_plain<Pixel, true, false>(b, f, d.thr, d.ref);
    case MomentKind::kThresholdedCount:
      return moments_plain<Pixel, false, true>(b, f, d.thr, nullptr);
    case MomentKind::kStart:
      return moments_plain<Pixel, false, false, true>(b, f, d.thr, nullptr);
    case MomentKind::kThresholded:
      break;
  }
  return moments_plain<Pixel, false, false>(b, f, d.thr, nullptr);
}

// --- Gaussian-weighted score -------------------------------------------------------------------

// Fills w[k] = exp(-a u^2), u = first + k - c, for k in [0, n), and with kMoments w*u and w*u^2
// beside it. Each weight on its own: no drift along the window, and the same to the last bit on
// both sides of c.
template <bool kMoments>
[[gnu::always_inline]] inline void gaussian_weights(int first, int n, double c, double a, float* w,
                                                    float* wu, float* wu2) noexcept {
  const auto af = static_cast<float>(a);
  const auto u0 = static_cast<float>(first - c);
  for (int k = 0; k < n; ++k) {
    const float u = u0 + static_cast<float>(k);
    const float wk = exp_nonpositive(-af * u * u);
    w[k] = wk;
    if constexpr (kMoments) {
      wu[k] = wk * u;
      wu2[k] = wk * u * u;
    }
  }
}

constexpr float kZeros[kGaussPad] = {};

template <typename Pixel>
[[gnu::always_inline]] inline GaussSums gauss_body(const Block& b, const FrameRef& f,
                                                   const BlockData& data,
                                                   const GaussWindow& w) noexcept {
  // Column weights over the window, 0 for kGaussPad columns either side (the groups below read
  // up to 15 columns beyond it); row weights over the window's rows.
  const int first = w.col_lo - b.x0;
  const int end = w.col_hi - b.x0 + 1;
  for (float* v : {w.wx, w.wxu, w.wxu2}) {
    std::memcpy(v + first - kGaussPad, kZeros, sizeof kZeros);
    std::memcpy(v + end, kZeros, sizeof kZeros);
  }
  gaussian_weights<true>(w.col_lo, end - first, w.cx, w.a_x, w.wx + first, w.wxu + first,
                         w.wxu2 + first);
  gaussian_weights<false>(w.row_lo, w.row_hi - w.row_lo + 1, w.cy, w.a_y, w.wy, nullptr, nullptr);
  const std::int32_t* ref = data.ref;
  // Columns of the block to read: the window, widened to whole groups of 16 (weights outside
  // the window are 0).
  const bool vector = b.width % 16 == 0;
  const int c_lo = vector ? std::max(0, w.col_lo - b.x0) / 16 * 16 : std::max(0, w.col_lo - b.x0);
  const int c_hi = std::min(b.width, w.col_hi - b.x0 + 1);
  f32x8 t0 = {};
  f32x8 t1x = {};
  f32x8 t2x = {};
  f32x8 t1y = {};
  f32x8 t2y = {};
  double s0 = 0, s1x = 0, s2x = 0, s1y = 0, s2y = 0;
  const i32x8 zero = {};
  const i32x8 outside = i32x8{} - (kOutsideDisk / 2);
  for (int y = w.row_lo; y <= w.row_hi; ++y) {
    const int r = y - b.y0;
    const Pixel* p = f.pixel<Pixel>(b.x0, y);
    const std::int32_t* rf = ref + row_at(b, r);
    const float wy = w.wy[y - w.row_lo];
    const float v = static_cast<float>(y - w.cy);
    if (vector) {
      f32x8 a0 = {};
      f32x8 a1 = {};
      f32x8 a2 = {};
      for (int g = c_lo; g < c_hi; g += 16) {
        u16x16 v16;
        if constexpr (sizeof(Pixel) == 1) {
          u8x16 p8;
          std::memcpy(&p8, p + g, sizeof p8);
          v16 = __builtin_convertvector(p8, u16x16);
        } else {
          std::memcpy(&v16, p + g, sizeof v16);
        }
        const u32x8 halves[2] = {TACTILE_LOW_HALF(v16), TACTILE_HIGH_HALF(v16)};
        for (int h = 0; h < 2; ++h) {
          const int k = g + 8 * h;
          i32x8 rv;
          std::memcpy(&rv, rf + k, sizeof rv);
          i32x8 d = (reinterpret_cast<i32x8>(halves[h]) << 8) - rv;
          d = d > outside ? d : zero;  // pixels outside the disk carry a huge reference
          f32x8 wxv;
          f32x8 wuv;
          f32x8 wu2v;
          std::memcpy(&wxv, w.wx + k, sizeof wxv);
          std::memcpy(&wuv, w.wxu + k, sizeof wuv);
          std::memcpy(&wu2v, w.wxu2 + k, sizeof wu2v);
          const f32x8 df = __builtin_convertvector(d, f32x8);
          a0 += df * wxv;
          a1 += df * wuv;
          a2 += df * wu2v;
        }
      }
      t0 += a0 * wy;
      t1x += a1 * wy;
      t2x += a2 * wy;
      t1y += a0 * (wy * v);
      t2y += a0 * (wy * v * v);
    } else {
      double r0 = 0, r1 = 0, r2 = 0;
      for (int k = c_lo; k < c_hi; ++k) {
        if (rf[k] >= kOutsideDisk / 2) continue;
        const double d = (static_cast<std::int32_t>(p[k]) << 8) - rf[k];
        r0 += d * static_cast<double>(w.wx[k]);
        r1 += d * static_cast<double>(w.wxu[k]);
        r2 += d * static_cast<double>(w.wxu2[k]);
      }
      s0 += r0 * static_cast<double>(wy);
      s1x += r1 * static_cast<double>(wy);
      s2x += r2 * static_cast<double>(wy);
      s1y += r0 * static_cast<double>(wy * v);
      s2y += r0 * static_cast<double>(wy * v * v);
    }
  }
  GaussSums out{s0, s1x, s2x, s1y, s2y};
  for (int j = 0; j < 8; ++j) {
    out.s0 += static_cast<double>(t0[j]);
    out.s1x += static_cast<double>(t1x[j]);
    out.s2x += static_cast<double>(t2x[j]);
    out.s1y += static_cast<double>(t1y[j]);
    out.s2y += static_cast<double>(t2y[j]);
  }
  return out;
}

TACTILE_CLONES
GSum exact_g_u8(const Block& b, const FrameRef& f, const BlockData& d) noexcept {
  if (b.width % 16 == 0) return exact_g_vec8(b, f, d.thr_hi8, d.thr_lo);
  return exact_g_plain<std::uint8_t>(b, f, d.thr_hi8, d.thr_lo);
}

TACTILE_CLONES
GSum exact_g_u16(const Block& b, const FrameRef& f, const BlockData& d) noexcept {
  return exact_g_plain<std::uint16_t>(b, f, d.thr_hi16, d.thr_lo);
}

TACTILE_CLONES
Moments moments_u8(const Block& b, const FrameRef& f, const BlockData& d,
                   MomentKind kind) noexcept {
  return moments_dispatch<std::uint8_t>(b, f, d, kind);
}

TACTILE_CLONES
Moments moments_u16(const Block& b, const FrameRef& f, const BlockData& d,
                    MomentKind kind) noexcept {
  return moments_dispatch<std::uint16_t>(b, f, d, kind);
}

TACTILE_CLONES
GaussSums gauss_u8(const Block& b, const FrameRef& f, const BlockData& d,
                   const GaussWindow& w) noexcept {
  return gauss_body<std::uint8_t>(b, f, d, w);
}

TACTILE_CLONES
GaussSums gauss_u16(const Block& b, const FrameRef& f, const BlockData& d,
                    const GaussWindow& w) noexcept {
  return gauss_body<std::uint16_t>(b, f, d, w);
}

}  // namespace

const KernelSet& portable_kernels() noexcept {
  static constexpr KernelSet kSet{"portable",  exact_g_u8, exact_g_u16, moments_u8,
                                  moments_u16, gauss_u8,   gauss_u16};
  return kSet;
}

const KernelSet& best_kernels() noexcept {
  const KernelSet* fast = avx2_kernels();
  return fast != nullptr ? *fast : portable_kernels();
}

}  // namespace tactile::detail
