#include <algorithm>
#include <cstdint>

#include "tactile/control/slip_detector.hpp"
#include "tactile/detail/multiversion.hpp"

#ifdef TACTILE_AVX2
#include <immintrin.h>
#endif

// The learned detector's model (docs/slip.md, "The learned combiner"): the compiled-in boosted
// trees and their scoring, by element (model_score) and by a frame's columns, portable and AVX2.
namespace tactile::control {

namespace {

// The compiled-in model of the learned detector (slip_train writes it).
#include "slip_model.inc"

static_assert(kSlipModel.features == kSlipFeatures,
              "slip_model.inc was trained on another feature set: run slip_train again");
static_assert(kSlipModel.depth >= 1 && kSlipModel.depth <= 8, "slip_train fits depths 1 to 8");

// The compiled-in model over `n` elements' signals by column, tree by tree: each split compares
// one column with one threshold; each element's leaves are summed in model_score's order, in
// float: the same scores, so the same decisions.
void score_portable(const SlipColumns& columns, std::size_t n, float* score) noexcept {
  std::array<std::uint32_t, kMaxSlipElements> leaf{};
  for (std::size_t e = 0; e < n; ++e)
    score[e] = static_cast<float>(kSlipModel.base);
  for (std::size_t t = 0; t < kSlipModel.trees; ++t) {
    for (std::size_t e = 0; e < n; ++e)
      leaf[e] = 0;
    for (std::size_t d = 0; d < kSlipModel.depth; ++d) {
      const std::size_t split = t * kSlipModel.depth + d;
      const float* column = columns[kSlipModelFeature[split]].data();
      const float threshold = kSlipModelThreshold[split];
      for (std::size_t e = 0; e < n; ++e)
        leaf[e] |= static_cast<std::uint32_t>(column[e] > threshold) << d;
    }
    const float* leaves = &kSlipModelLeaf[t << kSlipModel.depth];
    for (std::size_t e = 0; e < n; ++e)
      score[e] += leaves[leaf[e]];
  }
}

#ifdef TACTILE_AVX2

constexpr std::size_t kSplits = kSlipModel.trees * kSlipModel.depth;
// Trees whose leaf indices the AVX2 scoring holds at once (4 KB).
constexpr std::size_t kTreeChunk = 64;

// The model's thresholds by signal, at compile time: each signal's distinct thresholds in
// ascending order, and each split's rank among its signal's. With an element's count of a
// signal's thresholds below its value, `value > threshold` of the split is `count > rank`, exactly
// (the thresholds below a value are the first `count`; NaN is below none, as for `>`).
struct ThresholdRanks {
  std::array<std::size_t, kSlipFeatures + 1> begin{};  // signal k's: [begin[k], begin[k + 1])
  std::array<float, kSplits> ascending{};
  std::array<std::int8_t, kSplits> rank{};  // of each split, minus 128 (compared signed)
  std::size_t most = 0;                     // thresholds of the signal that has the most
};

constexpr ThresholdRanks rank_thresholds() {
  ThresholdRanks r;
  std::size_t size = 0;
  for (std::size_t k = 0; k < kSlipFeatures; ++k) {
    r.begin[k] = size;
    for (std::size_t s = 0; s < kSplits; ++s) {
      if (kSlipModelFeature[s] != k) continue;
      const float v = kSlipModelThreshold[s];
      std::size_t i = r.begin[k];
      while (i < size && r.ascending[i] < v)
        ++i;
      if (i < size && r.ascending[i] == v) continue;
      for (std::size_t j = size; j > i; --j)
        r.ascending[j] = r.ascending[j - 1];
      r.ascending[i] = v;
      ++size;
    }
    r.most = std::max(r.most, size - r.begin[k]);
  }
  r.begin[kSlipFeatures] = size;
  for (std::size_t s = 0; s < kSplits; ++s) {
    const std::size_t k = kSlipModelFeature[s];
    std::size_t i = r.begin[k];
    while (r.ascending[i] != kSlipModelThreshold[s])
      ++i;
    r.rank[s] = static_cast<std::int8_t>(static_cast<int>(i - r.begin[k]) - 128);
  }
  return r;
}

inline constexpr ThresholdRanks kRanks = rank_thresholds();
static_assert(kRanks.most <= 255, "a signal's count of thresholds must fit in a byte");

// Pass 1 for `Q` blocks of 8 elements from `first` (a multiple of 32): each signal's count of
// thresholds below each element's value, minus 128, in signed bytes (the blocks past Q count 0).
template <std::size_t Q>
TACTILE_AVX2 void count_thresholds_avx2(
    const SlipColumns& columns, std::size_t first,
    std::int8_t (&count)[kSlipFeatures][kMaxSlipElements]) noexcept {
  for (std::size_t k = 0; k < kSlipFeatures; ++k) {
    if (kRanks.begin[k] == kRanks.begin[k + 1]) continue;  // no split on it
    const float* column = columns[k].data() + first;
    __m256i c[4];
    for (auto& v : c)
      v = _mm256_set1_epi32(-128);
    for (std::size_t j = kRanks.begin[k]; j < kRanks.begin[k + 1]; ++j) {
      const __m256 threshold = _mm256_set1_ps(kRanks.ascending[j]);
      for (std::size_t q = 0; q < Q; ++q) {
        const __m256 above = _mm256_cmp_ps(_mm256_loadu_ps(column + 8 * q), threshold, _CMP_GT_OQ);
        c[q] = _mm256_sub_epi32(c[q], _mm256_castps_si256(above));
      }
    }
    // The packs interleave 128-bit lanes; the permutation undoes it.
    const __m256i bytes =
        _mm256_packs_epi16(_mm256_packs_epi32(c[0], c[1]), _mm256_packs_epi32(c[2], c[3]));
    _mm256_store_si256(
        reinterpret_cast<__m256i*>(count[k] + first),
        _mm256_permutevar8x32_epi32(bytes, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7)));
  }
}

// Pass 3 for `B` blocks of 8 elements from block `b`: trees [first, first + trees) of the chunk
// whose leaf indices `leaf` holds, added to `score` tree by tree. The blocks' sums are independent
// chains, so the gathers of one tree overlap.
template <std::size_t B>
TACTILE_AVX2 void sum_leaves_avx2(const std::uint8_t (&leaf)[kTreeChunk][kMaxSlipElements],
                                  std::size_t first, std::size_t trees, std::size_t b,
                                  float* score) noexcept {
  __m256 sum[B];
  for (std::size_t q = 0; q < B; ++q)
    sum[q] = _mm256_loadu_ps(score + 8 * (b + q));
  for (std::size_t t = 0; t < trees; ++t) {
    const float* leaves = &kSlipModelLeaf[(first + t) << kSlipModel.depth];
    for (std::size_t q = 0; q < B; ++q) {
      const __m256i index = _mm256_cvtepu8_epi32(
          _mm_loadl_epi64(reinterpret_cast<const __m128i*>(leaf[t] + 8 * (b + q))));
      sum[q] = _mm256_add_ps(sum[q], _mm256_i32gather_ps(leaves, index, 4));
    }
  }
  for (std::size_t q = 0; q < B; ++q)
    _mm256_storeu_ps(score + 8 * (b + q), sum[q]);
}

// The same scores in AVX2, compiled by function attribute only (the build has no -mavx2) and used
// only where the processor has it. Three passes over the frame's elements, 32 at a time in bytes
// where they can be:
//   1. each signal's count of thresholds below each element's value (8 floats per comparison);
//   2. each tree's leaf index from the counts (32 elements per comparison);
//   3. each element's leaves summed tree by tree, as model_score (8 elements per gather).
TACTILE_AVX2 void score_avx2(const SlipColumns& columns, std::size_t n, float* score) noexcept {
  static_assert(kMaxSlipElements % 32 == 0);
  constexpr std::size_t kDepth = kSlipModel.depth;
  const std::size_t halves = (n + 31) / 32;  // of 32 elements; the columns hold 64
  alignas(32) std::int8_t count[kSlipFeatures][kMaxSlipElements];
  for (std::size_t h = 0; h < halves; ++h) {
    switch (std::min<std::size_t>((n - 32 * h + 7) / 8, 4)) {
      case 1:
        count_thresholds_avx2<1>(columns, 32 * h, count);
        break;
      case 2:
        count_thresholds_avx2<2>(columns, 32 * h, count);
        break;
      case 3:
        count_thresholds_avx2<3>(columns, 32 * h, count);
        break;
      default:
        count_thresholds_avx2<4>(columns, 32 * h, count);
        break;
    }
  }
  // Passes 2 and 3 by chunks of trees.
  alignas(32) std::uint8_t leaf[kTreeChunk][kMaxSlipElements];
  const std::size_t blocks = (n + 7) / 8;
  for (std::size_t b = 0; b < blocks; ++b)
    _mm256_storeu_ps(score + 8 * b, _mm256_set1_ps(static_cast<float>(kSlipModel.base)));
  for (std::size_t first = 0; first < kSlipModel.trees; first += kTreeChunk) {
    const std::size_t trees = std::min(kTreeChunk, kSlipModel.trees - first);
    for (std::size_t t = 0; t < trees; ++t) {
      for (std::size_t h = 0; h < halves; ++h) {
        // Bit d of the index is split d's answer: from the last split to the first, the index
        // doubles and the answer (all ones, -1, when true) is subtracted.
        __m256i index = _mm256_setzero_si256();
        for (std::size_t d = kDepth; d-- > 0;) {
          const std::size_t split = (first + t) * kDepth + d;
          const __m256i c = _mm256_load_si256(
              reinterpret_cast<const __m256i*>(count[kSlipModelFeature[split]] + 32 * h));
          const __m256i above = _mm256_cmpgt_epi8(c, _mm256_set1_epi8(kRanks.rank[split]));
          index = _mm256_sub_epi8(_mm256_add_epi8(index, index), above);
        }
        _mm256_store_si256(reinterpret_cast<__m256i*>(leaf[t] + 32 * h), index);
      }
    }
    std::size_t b = 0;
    for (; b + 4 <= blocks; b += 4)
      sum_leaves_avx2<4>(leaf, first, trees, b, score);
    switch (blocks - b) {
      case 3:
        sum_leaves_avx2<3>(leaf, first, trees, b, score);
        break;
      case 2:
        sum_leaves_avx2<2>(leaf, first, trees, b, score);
        break;
      case 1:
        sum_leaves_avx2<1>(leaf, first, trees, b, score);
        break;
      default:
        break;
    }
  }
}
#endif

using ScoreFn = void (*)(const SlipColumns&, std::size_t, float*) noexcept;

ScoreFn vector_scoring() noexcept {
#ifdef TACTILE_AVX2
  if (tactile::detail::cpu_has_avx2_fma()) return score_avx2;
#endif
  return nullptr;
}

// Chosen once, at start-up.
const ScoreFn kVectorScoring = vector_scoring();

}  // namespace

// Summed in float, tree by tree, as the detector's batch evaluation: the same decisions.
double SlipDetector::model_score(const SlipFeatures& x) noexcept {
  auto score = static_cast<float>(kSlipModel.base);
  for (std::size_t t = 0; t < kSlipModel.trees; ++t) {
    std::size_t leaf = 0;
    for (std::size_t d = 0; d < kSlipModel.depth; ++d) {
      const std::size_t split = t * kSlipModel.depth + d;
      leaf |= static_cast<std::size_t>(x[kSlipModelFeature[split]] > kSlipModelThreshold[split])
              << d;
    }
    score += kSlipModelLeaf[(t << kSlipModel.depth) + leaf];
  }
  return static_cast<double>(score);
}

void SlipDetector::model_scores(const SlipColumns& columns, std::size_t n,
                                std::array<float, kMaxSlipElements>& score,
                                ModelScoring scoring) noexcept {
  n = std::min(n, kMaxSlipElements);
  if (scoring == ModelScoring::kVector && kVectorScoring != nullptr) {
    kVectorScoring(columns, n, score.data());
  } else {
    score_portable(columns, n, score.data());
  }
}

const char* SlipDetector::model_scoring() noexcept {
  return kVectorScoring != nullptr ? "avx2" : "portable";
}

double SlipDetector::model_decision() noexcept {
  return static_cast<double>(static_cast<float>(kSlipModel.decision));
}

std::size_t SlipDetector::model_trees() noexcept {
  return kSlipModel.trees;
}

}  // namespace tactile::control
