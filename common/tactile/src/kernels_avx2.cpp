// AVX2 kernels for 8- and 16-bit pixels, compiled for AVX2 and FMA by function attribute only (the
// build has no -mavx2), and used only where the processor has both (best_kernels()).
//
// Exact G and the thresholded moments come from one pass in 8-bit lanes, 32 pixels at a time:
// s = max(p - hi, 0) is one saturating subtract; sums of s and of the fractions lo are SAD
// instructions; sums of s * column are byte multiply-adds (column < 32 within a group of 32,
// the group's start added through the group's sum of s). Everything is exact. 16-bit pixels have
// their own pass (pass16, below); the Gaussian sums share one body for both depths.
#include "kernels.hpp"
#include "tactile/detail/multiversion.hpp"

#ifdef TACTILE_AVX2
#include <immintrin.h>

#include <algorithm>

namespace tactile::detail {
namespace {

TACTILE_AVX2_INLINE std::uint64_t sum_u64(__m256i v) noexcept {
  const __m128i s = _mm_add_epi64(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
  return static_cast<std::uint64_t>(_mm_cvtsi128_si64(s)) +
         static_cast<std::uint64_t>(_mm_extract_epi64(s, 1));
}

// Sum of eight non-negative 32-bit lanes, in 64 bits.
TACTILE_AVX2_INLINE __m256i widen_u32(__m256i v) noexcept {
  return _mm256_add_epi64(_mm256_cvtepu32_epi64(_mm256_castsi256_si128(v)),
                          _mm256_cvtepu32_epi64(_mm256_extracti128_si256(v, 1)));
}

// The largest of 32 byte lanes.
TACTILE_AVX2_INLINE std::int32_t max_u8(__m256i v) noexcept {
  __m128i m = _mm_max_epu8(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 8));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 4));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 2));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 1));
  return _mm_cvtsi128_si32(m) & 0xFF;
}

// The next row of a frame, stride bytes on.
template <typename Pixel>
TACTILE_AVX2_INLINE const Pixel* next_row(const Pixel* p, std::size_t stride) noexcept {
  return reinterpret_cast<const Pixel*>(reinterpret_cast<const std::uint8_t*>(p) + stride);
}

struct Sums8 {
  std::uint64_t s = 0, lo = 0, sx = 0, lx = 0, sy = 0, ly = 0;
  std::int64_t above = 0;
  std::int32_t peak = 0;
};

// One pass over a block whose width is a multiple of 32, with the threshold split (hi, lo), in
// groups of 32 columns: kGroups of them, or with kGroups = 0 as many as the block has. One group
// (every disk up to 32 pixels across) has no inner loop left. The row moments come from running
// sums, not a multiply per row: with T_r = sum of s over rows 0..r, sum_r r s_r = H S - sum_r T_r.
// The column sums are exact in 32-bit lanes, which a row grows by at most 2 * 2 * 255 * 31 per
// group: flushed into 64 bits before they could overflow (never within 65,536 rows of one group).
// kFractions: also the moments of the fractions lo (exact Q8 moments); without, the moments are
// those of s alone (MomentKind::kStart).
template <int kGroups, bool kMoments, bool kCount, bool kFractions>
TACTILE_AVX2_INLINE Sums8 pass8_groups(const Block& b, const FrameRef& f, const std::uint8_t* hi,
                                       const std::uint8_t* lo) noexcept {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i ones16 = _mm256_set1_epi16(1);
  const __m256i column =
      _mm256_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21,
                       22, 23, 24, 25, 26, 27, 28, 29, 30, 31);
  __m256i acc_s = zero;   // u64 lanes: S after the row
  __m256i acc_l = zero;   // u64 lanes
  __m256i acc_ts = zero;  // u64 lanes: sum of the running S
  __m256i acc_tl = zero;
  __m256i acc_sg = zero;  // u64 lanes: group start * group sum of s
  __m256i acc_lg = zero;
  __m256i acc_sx = zero;  // u32 lanes, flushed into sx64
  __m256i acc_lx = zero;
  __m256i sx64 = zero;
  __m256i lx64 = zero;
  __m256i peak = zero;
  std::int64_t above = 0;
  const int groups = kGroups > 0 ? kGroups : b.width / 32;
  const int width = 32 * groups;
  const int flush_rows = std::max(1, static_cast<int>((std::int64_t{1} << 31) / (groups * 31620)));
  int since_flush = 0;
  const std::uint8_t* p = f.pixel<std::uint8_t>(b.x0, b.y0);
  const std::uint8_t* h = hi + b.offset;
  const std::uint8_t* l = lo + b.offset;
  for (int r = 0; r < b.height; ++r, p += f.stride, h += width, l += width) {
    for (int g = 0; g < width; g += 32) {
      const __m256i pv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + g));
      const __m256i hv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h + g));
      const __m256i lv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(l + g));
      const __m256i s = _mm256_subs_epu8(pv, hv);
      const __m256i none = _mm256_cmpeq_epi8(s, zero);
      const __m256i lm = _mm256_andnot_si256(none, lv);
      const __m256i ss = _mm256_sad_epu8(s, zero);
      const __m256i ls = _mm256_sad_epu8(lm, zero);
      acc_s = _mm256_add_epi64(acc_s, ss);
      acc_l = _mm256_add_epi64(acc_l, ls);
      if constexpr (kMoments) {
        peak = _mm256_max_epu8(peak, s);
        acc_sx =
            _mm256_add_epi32(acc_sx, _mm256_madd_epi16(_mm256_maddubs_epi16(s, column), ones16));
        if constexpr (kFractions) {
          acc_lx =
              _mm256_add_epi32(acc_lx, _mm256_madd_epi16(_mm256_maddubs_epi16(lm, column), ones16));
        }
        if (g > 0) {
          const __m256i start = _mm256_set1_epi64x(g);
          acc_sg = _mm256_add_epi64(acc_sg, _mm256_mul_epu32(ss, start));
          if constexpr (kFractions) acc_lg = _mm256_add_epi64(acc_lg, _mm256_mul_epu32(ls, start));
        }
      }
      if constexpr (kCount) {
        above += 32 - __builtin_popcount(static_cast<unsigned>(_mm256_movemask_epi8(none)));
      }
    }
    if constexpr (kMoments) {
      acc_ts = _mm256_add_epi64(acc_ts, acc_s);
      if constexpr (kFractions) acc_tl = _mm256_add_epi64(acc_tl, acc_l);
      if (kGroups != 1 && ++since_flush == flush_rows) {
        sx64 = _mm256_add_epi64(sx64, widen_u32(acc_sx));
        lx64 = _mm256_add_epi64(lx64, widen_u32(acc_lx));
        acc_sx = zero;
        acc_lx = zero;
        since_flush = 0;
      }
    }
  }
  Sums8 out;
  out.s = sum_u64(acc_s);
  out.lo = sum_u64(acc_l);
  if constexpr (kMoments) {
    const auto rows = static_cast<std::uint64_t>(b.height);
    sx64 = _mm256_add_epi64(sx64, widen_u32(acc_sx));
    lx64 = _mm256_add_epi64(lx64, widen_u32(acc_lx));
    out.sx = sum_u64(sx64) + sum_u64(acc_sg);
    out.lx = sum_u64(lx64) + sum_u64(acc_lg);
    out.sy = rows * out.s - sum_u64(acc_ts);
    out.ly = rows * out.lo - sum_u64(acc_tl);
    out.peak = max_u8(peak);
  }
  out.above = above;
  return out;
}

template <bool kMoments, bool kCount, bool kFractions = true>
TACTILE_AVX2_INLINE Sums8 pass8(const Block& b, const FrameRef& f, const std::uint8_t* hi,
                                const std::uint8_t* lo) noexcept {
  if (b.width == 32 && b.height <= 65536) {
    return pass8_groups<1, kMoments, kCount, kFractions>(b, f, hi, lo);
  }
  return pass8_groups<0, kMoments, kCount, kFractions>(b, f, hi, lo);
}

TACTILE_AVX2 GSum exact_g_u8(const Block& b, const FrameRef& f, const BlockData& d) noexcept {
  if (b.width % 32 != 0) return portable_kernels().exact_g_u8(b, f, d);
  const Sums8 s = pass8<false, false>(b, f, d.thr_hi8, d.thr_lo);
  return {s.s, s.lo};
}

TACTILE_AVX2 Moments moments_u8(const Block& b, const FrameRef& f, const BlockData& d,
                                MomentKind kind) noexcept {
  if (b.width % 32 != 0) return portable_kernels().moments_u8(b, f, d, kind);
  const auto to_moments = [](const Sums8& s) {
    Moments m;
    m.g = static_cast<std::int64_t>(256 * s.s - s.lo);
    m.c0 = m.g;
    m.cx = static_cast<std::int64_t>(256 * s.sx - s.lx);
    m.cy = static_cast<std::int64_t>(256 * s.sy - s.ly);
    m.above = s.above;
    m.peak = s.peak;
    return m;
  };
  switch (kind) {
    case MomentKind::kThresholdedCount:
      return to_moments(pass8<true, true>(b, f, d.thr_hi8, d.thr_lo));
    case MomentKind::kPlain: {
      // G with the floor, the centroid without: two passes.
      Moments m = to_moments(pass8<true, false>(b, f, d.thr_hi8, d.thr_lo));
      const Moments c = to_moments(pass8<true, false>(b, f, d.ref_hi8, d.ref_lo));
      m.c0 = c.g;
      m.cx = c.cx;
      m.cy = c.cy;
      return m;
    }
    case MomentKind::kStart: {
      const Sums8 s = pass8<true, false, false>(b, f, d.thr_hi8, d.thr_lo);
      Moments m;
      m.g = static_cast<std::int64_t>(256 * s.s - s.lo);
      m.c0 = static_cast<std::int64_t>(s.s);
      m.cx = static_cast<std::int64_t>(s.sx);
      m.cy = static_cast<std::int64_t>(s.sy);
      m.peak = s.peak;
      return m;
    }
    case MomentKind::kThresholded:
      break;
  }
  return to_moments(pass8<true, false>(b, f, d.thr_hi8, d.thr_lo));
}

// --- 16-bit pixels ------------------------------------------------------------------------------
//
// One pass in 16-bit lanes, 16 pixels at a time, over a block kV vectors wide: s = max(p - hi, 0)
// is one saturating subtract, the fraction lo (widened from bytes) kept where s > 0. Sums are
// 16-bit multiply-adds into 32-bit lanes. Those are signed and s reaches 65535, so they take
// s' = s - 32768 (s with its top bit flipped): each sum then falls short of the true one by what
// the same sums give for s = 0, a per-row constant put back at the end. Every 32-bit lane is
// summed modulo 2^32 and its true value stays below 2^32 (fits_pass16), so the lane sums come out
// exact, and so do their 64-bit totals. The row moments come from running sums as in the 8-bit
// pass: sum_r r s_r = H S - sum_r T_r. Exact like the portable loops.
//
// Whether pass16 takes the block: 32 or 64 columns (the blocks of every disk up to 64 pixels
// across; narrower ones arise only where the region of all disks is narrower, and take the
// portable loops), and few enough rows that a lane's sum of T_r, at most
// H (H + 1) / 2 x kV x 2 x 65535, stays below 2^32 (H up to 127 rows at 32 columns, 90 at 64:
// more than a disk that fits the block's width has).
bool fits_pass16(const Block& b) noexcept {
  const int v = b.width / 16;
  return (b.width == 32 || b.width == 64) &&
         static_cast<std::int64_t>(b.height) * (b.height + 1) * v < 32768;
}

// Sum of eight 32-bit lanes, each corrected by -k x bias (modulo 2^32), in 64 bits.
TACTILE_AVX2_INLINE std::uint64_t lanes_minus(__m256i acc, __m256i bias, std::uint32_t k) noexcept {
  alignas(32) std::uint32_t a[8];
  alignas(32) std::uint32_t c[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(a), acc);
  _mm256_store_si256(reinterpret_cast<__m256i*>(c), bias);
  std::uint64_t sum = 0;
  for (int j = 0; j < 8; ++j)
    sum += static_cast<std::uint32_t>(a[j] - k * c[j]);
  return sum;
}

template <int kV, bool kMoments, bool kCount, bool kFractions>
TACTILE_AVX2_INLINE Sums8 pass16(const Block& b, const FrameRef& f, const std::uint16_t* hi,
                                 const std::uint8_t* lo) noexcept {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i flip = _mm256_set1_epi16(static_cast<short>(0x8000));
  const __m256i ones = _mm256_set1_epi16(1);
  __m256i col[kV];
  for (int v = 0; v < kV; ++v) {
    col[v] =
        _mm256_add_epi16(_mm256_set1_epi16(static_cast<short>(16 * v)),
                         _mm256_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
  }
  __m256i acc_s = zero;   // sum of s' pairs
  __m256i acc_sx = zero;  // sum of s' x column
  __m256i acc_ts = zero;  // sum over rows of acc_s: the running T_r
  __m256i acc_l = zero;
  __m256i acc_lx = zero;
  __m256i acc_tl = zero;
  __m256i peak = zero;
  std::int64_t above = 0;
  const std::uint16_t* p = f.pixel<std::uint16_t>(b.x0, b.y0);
  const std::uint16_t* h = hi + b.offset;
  const std::uint8_t* l = lo + b.offset;
  for (int r = 0; r < b.height; ++r, p = next_row(p, f.stride), h += 16 * kV, l += 16 * kV) {
    for (int v = 0; v < kV; ++v) {
      const __m256i pv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 16 * v));
      const __m256i hv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h + 16 * v));
      const __m256i lv =
          _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(l + 16 * v)));
      const __m256i s = _mm256_subs_epu16(pv, hv);
      const __m256i none = _mm256_cmpeq_epi16(s, zero);
      const __m256i lm = _mm256_andnot_si256(none, lv);
      const __m256i sf = _mm256_xor_si256(s, flip);
      acc_s = _mm256_add_epi32(acc_s, _mm256_madd_epi16(sf, ones));
      acc_l = _mm256_add_epi32(acc_l, _mm256_madd_epi16(lm, ones));
      if constexpr (kMoments) {
        peak = _mm256_max_epu16(peak, s);
        acc_sx = _mm256_add_epi32(acc_sx, _mm256_madd_epi16(sf, col[v]));
        if constexpr (kFractions) acc_lx = _mm256_add_epi32(acc_lx, _mm256_madd_epi16(lm, col[v]));
      }
      if constexpr (kCount) {
        above += 16 - __builtin_popcount(static_cast<unsigned>(_mm256_movemask_epi8(none))) / 2;
      }
    }
    if constexpr (kMoments) {
      acc_ts = _mm256_add_epi32(acc_ts, acc_s);
      if constexpr (kFractions) acc_tl = _mm256_add_epi32(acc_tl, acc_l);
    }
  }
  // What the sums of s' give for s = 0, per row, lane by lane.
  __m256i bias_s = zero;
  __m256i bias_sx = zero;
  for (int v = 0; v < kV; ++v) {
    bias_s = _mm256_add_epi32(bias_s, _mm256_madd_epi16(flip, ones));
    bias_sx = _mm256_add_epi32(bias_sx, _mm256_madd_epi16(flip, col[v]));
  }
  const auto rows = static_cast<std::uint32_t>(b.height);
  Sums8 out;
  out.s = lanes_minus(acc_s, bias_s, rows);
  out.lo = lanes_minus(acc_l, zero, 0);
  if constexpr (kMoments) {
    out.sx = lanes_minus(acc_sx, bias_sx, rows);
    out.lx = lanes_minus(acc_lx, zero, 0);
    // The running sums fell short by (r + 1) x bias after row r: H (H + 1) / 2 x bias in all.
    out.sy = rows * out.s - lanes_minus(acc_ts, bias_s, rows * (rows + 1) / 2);
    out.ly = rows * out.lo - lanes_minus(acc_tl, zero, 0);
    __m128i m = _mm_max_epu16(_mm256_castsi256_si128(peak), _mm256_extracti128_si256(peak, 1));
    m = _mm_max_epu16(m, _mm_srli_si128(m, 8));
    m = _mm_max_epu16(m, _mm_srli_si128(m, 4));
    m = _mm_max_epu16(m, _mm_srli_si128(m, 2));
    out.peak = _mm_cvtsi128_si32(m) & 0xFFFF;
  }
  out.above = above;
  return out;
}

template <bool kMoments, bool kCount, bool kFractions = true>
TACTILE_AVX2_INLINE Sums8 pass16_any(const Block& b, const FrameRef& f, const std::uint16_t* hi,
                                     const std::uint8_t* lo) noexcept {
  if (b.width == 32) return pass16<2, kMoments, kCount, kFractions>(b, f, hi, lo);
  return pass16<4, kMoments, kCount, kFractions>(b, f, hi, lo);
}

TACTILE_AVX2 GSum exact_g_u16(const Block& b, const FrameRef& f, const BlockData& d) noexcept {
  if (!fits_pass16(b)) return portable_kernels().exact_g_u16(b, f, d);
  const Sums8 s = pass16_any<false, false, false>(b, f, d.thr_hi16, d.thr_lo);
  return {s.s, s.lo};
}

TACTILE_AVX2 Moments moments_u16(const Block& b, const FrameRef& f, const BlockData& d,
                                 MomentKind kind) noexcept {
  // kPlain's centroid weights need the reference split, which 16-bit sensors do not keep.
  if (!fits_pass16(b) || kind == MomentKind::kPlain) {
    return portable_kernels().moments_u16(b, f, d, kind);
  }
  const Sums8 s =
      kind == MomentKind::kThresholdedCount ? pass16_any<true, true>(b, f, d.thr_hi16, d.thr_lo)
      : kind == MomentKind::kStart ? pass16_any<true, false, false>(b, f, d.thr_hi16, d.thr_lo)
                                   : pass16_any<true, false>(b, f, d.thr_hi16, d.thr_lo);
  Moments m;
  m.g = static_cast<std::int64_t>(256 * s.s - s.lo);
  m.peak = s.peak;
  m.above = s.above;
  if (kind == MomentKind::kStart) {
    // Whole gray levels above the threshold: s itself.
    m.c0 = static_cast<std::int64_t>(s.s);
    m.cx = static_cast<std::int64_t>(s.sx);
    m.cy = static_cast<std::int64_t>(s.sy);
  } else {
    m.c0 = m.g;
    m.cx = static_cast<std::int64_t>(256 * s.sx - s.lx);
    m.cy = static_cast<std::int64_t>(256 * s.sy - s.ly);
  }
  return m;
}

TACTILE_AVX2_INLINE double hsum(__m256 v) noexcept {
  const __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 t = _mm_add_ps(s, _mm_movehl_ps(s, s));
  return static_cast<double>(_mm_cvtss_f32(_mm_add_ss(t, _mm_shuffle_ps(t, t, 1))));
}

// One group of 8 pixels of a row: d = 256 p - ref (0 outside the disk) times the column
// weights, into three partial sums.
// exp_nonpositive, eight lanes at a time (the same steps; the polynomial with fused
// multiply-adds, so the last bit may differ).
TACTILE_AVX2_INLINE __m256 exp8_nonpositive(__m256 x) noexcept {
  const __m256 t = _mm256_mul_ps(x, _mm256_set1_ps(1.44269504F));
  const __m256i ni = _mm256_cvttps_epi32(_mm256_sub_ps(t, _mm256_set1_ps(0.5F)));
  const __m256 n = _mm256_cvtepi32_ps(ni);
  const __m256 r = _mm256_sub_ps(_mm256_sub_ps(x, _mm256_mul_ps(n, _mm256_set1_ps(0.693145752F))),
                                 _mm256_mul_ps(n, _mm256_set1_ps(1.42860677e-6F)));
  __m256 p = _mm256_set1_ps(1.0F / 720);
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0F / 120));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0F / 24));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0F / 6));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(0.5F));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0F));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0F));
  const __m256i scale = _mm256_slli_epi32(_mm256_add_epi32(ni, _mm256_set1_epi32(127)), 23);
  return _mm256_mul_ps(p, _mm256_castsi256_ps(scale));
}

// d = 256 p - ref of 8 pixels of a row from column k as floats; with kMasked 0 outside the disk
// (the reference of an 8-bit sensor is at most 65280 in Q8; 65535 marks the pixels outside).
template <bool kMasked>
TACTILE_AVX2_INLINE __m256 increments8(const std::uint8_t* p, const std::uint16_t* rf, int k,
                                       __m256i outside) noexcept {
  const __m256i pv = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + k)));
  const __m256i rv =
      _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(rf + k)));
  const __m256i dv = _mm256_sub_epi32(_mm256_slli_epi32(pv, 8), rv);
  if constexpr (!kMasked) return _mm256_cvtepi32_ps(dv);
  return _mm256_cvtepi32_ps(_mm256_andnot_si256(_mm256_cmpeq_epi32(rv, outside), dv));
}

// The same for 16-bit pixels, against the 32-bit reference (kOutsideDisk outside the disk). In
// the disk |d| < 2^24: exact as a float, as the portable kernel's is.
template <bool kMasked>
TACTILE_AVX2_INLINE __m256 increments8(const std::uint16_t* p, const std::int32_t* rf, int k,
                                       __m256i outside) noexcept {
  const __m256i pv =
      _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + k)));
  const __m256i rv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(rf + k));
  const __m256i dv = _mm256_sub_epi32(_mm256_slli_epi32(pv, 8), rv);
  if constexpr (!kMasked) return _mm256_cvtepi32_ps(dv);
  return _mm256_cvtepi32_ps(_mm256_andnot_si256(_mm256_cmpeq_epi32(rv, outside), dv));
}

// The reference the Gaussian kernels read, and its mark outside the disk, per pixel type.
TACTILE_AVX2_INLINE const std::uint16_t* gauss_ref(const BlockData& d, std::uint8_t /*tag*/) {
  return d.ref16;
}
TACTILE_AVX2_INLINE const std::int32_t* gauss_ref(const BlockData& d, std::uint16_t /*tag*/) {
  return d.ref;
}
template <typename Pixel>
constexpr std::int32_t kRefOutside = sizeof(Pixel) == 1 ? 65535 : kOutsideDisk;

// Column weights of the group of 8 from block column k: exp(-a u^2) inside the window
// [first, end), 0 outside; u, from the column's centre to the window's centre.
TACTILE_AVX2_INLINE __m256 column_weights(const Block& b, const GaussWindow& w, int k, int first,
                                          int end, __m256& u) noexcept {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i col = _mm256_add_epi32(_mm256_set1_epi32(k), lane);
  const __m256i in = _mm256_and_si256(_mm256_cmpgt_epi32(col, _mm256_set1_epi32(first - 1)),
                                      _mm256_cmpgt_epi32(_mm256_set1_epi32(end), col));
  u = _mm256_add_ps(_mm256_set1_ps(static_cast<float>(b.x0 + k - w.cx)), _mm256_cvtepi32_ps(lane));
  const __m256 e = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(-static_cast<float>(w.a_x)), u), u);
  return _mm256_and_ps(exp8_nonpositive(e), _mm256_castsi256_ps(in));
}

// The Gaussian sums of a window kGroups groups of 8 wide (up to 32 columns, the commonest),
// column by column: each group's increments summed down the rows with the row weights
// (wy, wy v, wy v^2), and only then weighed by the column weights, which stay in registers. The
// row weights are in w.wy. Without kMasked every pixel of the window must lie in the disk: the
// groups' columns outside the window may not, but their increments are finite and their
// column weights exactly 0.
template <typename Pixel, int kGroups, bool kMasked>
TACTILE_AVX2_INLINE GaussSums gauss_columns(const Block& b, const FrameRef& f, const BlockData& d,
                                            const GaussWindow& w, int c_lo, int first,
                                            int end) noexcept {
  const __m256i outside = _mm256_set1_epi32(kRefOutside<Pixel>);
  __m256 c0[kGroups];
  __m256 c1[kGroups];
  __m256 c2[kGroups];
  for (int g = 0; g < kGroups; ++g) {
    c0[g] = _mm256_setzero_ps();
    c1[g] = _mm256_setzero_ps();
    c2[g] = _mm256_setzero_ps();
  }
  const Pixel* p = f.pixel<Pixel>(b.x0, w.row_lo);
  const auto* rf = gauss_ref(d, Pixel{}) + b.offset +
                   static_cast<std::size_t>(w.row_lo - b.y0) * static_cast<std::size_t>(b.width);
  const auto v0 = static_cast<float>(w.row_lo - w.cy);
  const int rows = w.row_hi - w.row_lo + 1;
  for (int j = 0; j < rows; ++j, p = next_row(p, f.stride), rf += b.width) {
    const float wy = w.wy[j];
    const float v = v0 + static_cast<float>(j);
    const __m256 b0 = _mm256_set1_ps(wy);
    const __m256 b1 = _mm256_set1_ps(wy * v);
    const __m256 b2 = _mm256_set1_ps(wy * v * v);
    for (int g = 0; g < kGroups; ++g) {
      const __m256 dv = increments8<kMasked>(p, rf, c_lo + 8 * g, outside);
      c0[g] = _mm256_fmadd_ps(dv, b0, c0[g]);
      c1[g] = _mm256_fmadd_ps(dv, b1, c1[g]);
      c2[g] = _mm256_fmadd_ps(dv, b2, c2[g]);
    }
  }
  __m256 t0 = _mm256_setzero_ps();
  __m256 t1x = _mm256_setzero_ps();
  __m256 t2x = _mm256_setzero_ps();
  __m256 t1y = _mm256_setzero_ps();
  __m256 t2y = _mm256_setzero_ps();
  for (int g = 0; g < kGroups; ++g) {
    __m256 u;
    const __m256 wx = column_weights(b, w, c_lo + 8 * g, first, end, u);
    const __m256 wxu = _mm256_mul_ps(wx, u);
    t0 = _mm256_fmadd_ps(c0[g], wx, t0);
    t1x = _mm256_fmadd_ps(c0[g], wxu, t1x);
    t2x = _mm256_fmadd_ps(c0[g], _mm256_mul_ps(wxu, u), t2x);
    t1y = _mm256_fmadd_ps(c1[g], wx, t1y);
    t2y = _mm256_fmadd_ps(c2[g], wx, t2y);
  }
  return {hsum(t0), hsum(t1x), hsum(t2x), hsum(t1y), hsum(t2y)};
}

// gauss_columns without the outside test where the window lies in the disk.
template <typename Pixel, int kGroups>
TACTILE_AVX2_INLINE GaussSums gauss_columns_either(const Block& b, const FrameRef& f,
                                                   const BlockData& d, const GaussWindow& w,
                                                   int c_lo, int first, int end) noexcept {
  return w.inside_disk ? gauss_columns<Pixel, kGroups, false>(b, f, d, w, c_lo, first, end)
                       : gauss_columns<Pixel, kGroups, true>(b, f, d, w, c_lo, first, end);
}

template <typename Pixel>
TACTILE_AVX2_INLINE GaussSums gauss_any(const Block& b, const FrameRef& f, const BlockData& d,
                                        const GaussWindow& w) noexcept {
  // Groups of 8 from the window's first column (unaligned), moved left where the last group
  // would leave the block; the column weights are computed for exactly those groups, 0 outside
  // the window. The row weights go to w.wy first.
  const int first = std::max(0, w.col_lo - b.x0);
  const int end = std::min(b.width, w.col_hi - b.x0 + 1);
  const int groups = (end - first + 7) / 8;
  const int c_lo = std::max(0, std::min(first, b.width - 8 * groups));
  const int c_hi = std::min(b.width, c_lo + 8 * groups);
  {
    const __m256 minus_a = _mm256_set1_ps(-static_cast<float>(w.a_y));
    const __m256 lane = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7);
    const int rows = w.row_hi - w.row_lo + 1;
    const auto v_lo = static_cast<float>(w.row_lo - w.cy);
    for (int j = 0; j < rows; j += 8) {
      const __m256 v = _mm256_add_ps(_mm256_set1_ps(v_lo + static_cast<float>(j)), lane);
      _mm256_storeu_ps(w.wy + j, exp8_nonpositive(_mm256_mul_ps(_mm256_mul_ps(minus_a, v), v)));
    }
  }
  // The window in strips of up to four groups (32 columns: one strip for every window on a disk
  // up to 32 pixels across), each summed column by column, the strips' sums added.
  GaussSums out;
  for (int c = c_lo; c < c_hi; c += 32) {
    GaussSums part;
    switch (std::min(4, (c_hi - c) / 8)) {
      case 1:
        part = gauss_columns_either<Pixel, 1>(b, f, d, w, c, first, end);
        break;
      case 2:
        part = gauss_columns_either<Pixel, 2>(b, f, d, w, c, first, end);
        break;
      case 3:
        part = gauss_columns_either<Pixel, 3>(b, f, d, w, c, first, end);
        break;
      default:
        part = gauss_columns_either<Pixel, 4>(b, f, d, w, c, first, end);
        break;
    }
    out.s0 += part.s0;
    out.s1x += part.s1x;
    out.s2x += part.s2x;
    out.s1y += part.s1y;
    out.s2y += part.s2y;
  }
  return out;
}

TACTILE_AVX2 GaussSums gauss_u8(const Block& b, const FrameRef& f, const BlockData& d,
                                const GaussWindow& w) noexcept {
  if (b.width % 8 != 0) return portable_kernels().gauss_u8(b, f, d, w);
  return gauss_any<std::uint8_t>(b, f, d, w);
}

TACTILE_AVX2 GaussSums gauss_u16(const Block& b, const FrameRef& f, const BlockData& d,
                                 const GaussWindow& w) noexcept {
  if (b.width % 8 != 0) return portable_kernels().gauss_u16(b, f, d, w);
  return gauss_any<std::uint16_t>(b, f, d, w);
}

}  // namespace

const KernelSet* avx2_kernels() noexcept {
  static const KernelSet kSet{"avx2",      exact_g_u8, exact_g_u16, moments_u8,
                              moments_u16, gauss_u8,   gauss_u16};
  return cpu_has_avx2_fma() ? &kSet : nullptr;
}

}  // namespace tactile::detail

#else

namespace tactile::detail {

const KernelSet* avx2_kernels() noexcept {
  return nullptr;
}

}  // namespace tactile::detail

#endif
