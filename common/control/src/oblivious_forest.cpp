#include "tactile/control/oblivious_forest.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#ifdef TACTILE_AVX2
#include <immintrin.h>
#endif

namespace tactile::control {

namespace {

// Trees whose leaf indices the AVX2 scoring holds at once (4 KB).
constexpr std::size_t kTreeChunk = 64;

#ifdef TACTILE_AVX2
const bool kHasAvx2 = tactile::detail::cpu_has_avx2_fma();
#else
const bool kHasAvx2 = false;
#endif

}  // namespace

ObliviousForest::ObliviousForest(std::size_t features, std::size_t depth, double base,
                                 std::vector<std::uint8_t> feature, std::vector<float> threshold,
                                 std::vector<float> leaf)
    : features_(features),
      depth_(depth),
      base_(base),
      feature_(std::move(feature)),
      threshold_(std::move(threshold)),
      leaf_(std::move(leaf)) {
  const auto refuse = [](const std::string& what) {
    throw std::invalid_argument("oblivious forest: " + what);
  };
  if (features_ == 0 || features_ > kSlipFeatures)
    refuse("features must be 1.." + std::to_string(kSlipFeatures) + ", got " +
           std::to_string(features_));
  if (depth_ < 1 || depth_ > 8) refuse("depth must be 1..8, got " + std::to_string(depth_));
  if (!std::isfinite(base_)) refuse("the base score is not finite");
  if (feature_.size() % depth_ != 0 || threshold_.size() != feature_.size() ||
      leaf_.size() != (feature_.size() / depth_) << depth_)
    refuse("per tree " + std::to_string(depth_) + " splits and " +
           std::to_string(std::size_t{1} << depth_) + " leaves: got " +
           std::to_string(feature_.size()) + " features, " + std::to_string(threshold_.size()) +
           " thresholds, " + std::to_string(leaf_.size()) + " leaves");
  for (std::size_t s = 0; s < feature_.size(); ++s) {
    if (feature_[s] >= features_)
      refuse("split " + std::to_string(s) + " is on feature " + std::to_string(feature_[s]) +
             " of " + std::to_string(features_));
    if (std::isnan(threshold_[s])) refuse("split " + std::to_string(s) + "'s threshold is NaN");
  }

  // The thresholds by signal, for the vector path.
  rank_.assign(feature_.size(), 0);
  std::size_t most = 0;
  for (std::size_t k = 0; k < kSlipFeatures; ++k) {
    begin_[k] = ascending_.size();
    for (std::size_t s = 0; s < feature_.size(); ++s) {
      if (feature_[s] == k) ascending_.push_back(threshold_[s]);
    }
    const auto first = ascending_.begin() + static_cast<std::ptrdiff_t>(begin_[k]);
    std::sort(first, ascending_.end());
    ascending_.erase(std::unique(first, ascending_.end()), ascending_.end());
    most = std::max(most, ascending_.size() - begin_[k]);
  }
  begin_[kSlipFeatures] = ascending_.size();
  ranks_fit_ = most <= 255;
  for (std::size_t s = 0; ranks_fit_ && s < feature_.size(); ++s) {
    const std::size_t k = feature_[s];
    const auto first = ascending_.begin() + static_cast<std::ptrdiff_t>(begin_[k]);
    const auto last = ascending_.begin() + static_cast<std::ptrdiff_t>(begin_[k + 1]);
    const auto at = std::lower_bound(first, last, threshold_[s]) - first;
    rank_[s] = static_cast<std::int8_t>(static_cast<int>(at) - 128);
  }
}

float ObliviousForest::score(std::span<const float> x) const noexcept {
  auto score = static_cast<float>(base_);
  const std::size_t n = trees();
  for (std::size_t t = 0; t < n; ++t) {
    std::size_t leaf = 0;
    for (std::size_t d = 0; d < depth_; ++d) {
      const std::size_t split = t * depth_ + d;
      leaf |= static_cast<std::size_t>(x[feature_[split]] > threshold_[split]) << d;
    }
    score += leaf_[(t << depth_) + leaf];
  }
  return score;
}

// Tree by tree over the columns: each split compares one column with one threshold; each
// element's leaves are summed in score()'s order, in float: the same scores.
void ObliviousForest::score_portable(const SlipColumns& columns, std::size_t n,
                                     float* score) const noexcept {
  std::array<std::uint32_t, kMaxSlipElements> leaf{};
  for (std::size_t e = 0; e < n; ++e)
    score[e] = static_cast<float>(base_);
  const std::size_t trees = this->trees();
  for (std::size_t t = 0; t < trees; ++t) {
    for (std::size_t e = 0; e < n; ++e)
      leaf[e] = 0;
    for (std::size_t d = 0; d < depth_; ++d) {
      const std::size_t split = t * depth_ + d;
      const float* column = columns[feature_[split]].data();
      const float threshold = threshold_[split];
      for (std::size_t e = 0; e < n; ++e)
        leaf[e] |= static_cast<std::uint32_t>(column[e] > threshold) << d;
    }
    const float* leaves = &leaf_[t << depth_];
    for (std::size_t e = 0; e < n; ++e)
      score[e] += leaves[leaf[e]];
  }
}

#ifdef TACTILE_AVX2

namespace {

// Pass 1 for `Q` blocks of 8 elements from `first` (a multiple of 32): each signal's count of
// thresholds below each element's value, minus 128, in signed bytes (the blocks past Q count 0).
template <std::size_t Q>
TACTILE_AVX2 void count_thresholds_avx2(
    const SlipColumns& columns, std::size_t first,
    const std::array<std::size_t, kSlipFeatures + 1>& begin, const float* ascending,
    std::int8_t (&count)[kSlipFeatures][kMaxSlipElements]) noexcept {
  for (std::size_t k = 0; k < kSlipFeatures; ++k) {
    if (begin[k] == begin[k + 1]) continue;  // no split on it
    const float* column = columns[k].data() + first;
    __m256i c[4];
    for (auto& v : c)
      v = _mm256_set1_epi32(-128);
    for (std::size_t j = begin[k]; j < begin[k + 1]; ++j) {
      const __m256 threshold = _mm256_set1_ps(ascending[j]);
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

// Pass 3 for `B` blocks of 8 elements from block `b`: the `trees` trees of depth D whose leaf
// indices `leaf` holds (their leaves from `leaves`, 2^D each), added to `score` tree by tree. The
// blocks' sums are independent chains, so the gathers of one tree overlap.
template <std::size_t B, std::size_t D>
TACTILE_AVX2 void sum_leaves_avx2(const std::uint8_t (&leaf)[kTreeChunk][kMaxSlipElements],
                                  const float* leaves, std::size_t trees, std::size_t b,
                                  float* score) noexcept {
  __m256 sum[B];
  for (std::size_t q = 0; q < B; ++q)
    sum[q] = _mm256_loadu_ps(score + 8 * (b + q));
  for (std::size_t t = 0; t < trees; ++t) {
    const float* tree = leaves + (t << D);
    for (std::size_t q = 0; q < B; ++q) {
      const __m256i index = _mm256_cvtepu8_epi32(
          _mm_loadl_epi64(reinterpret_cast<const __m128i*>(leaf[t] + 8 * (b + q))));
      sum[q] = _mm256_add_ps(sum[q], _mm256_i32gather_ps(tree, index, 4));
    }
  }
  for (std::size_t q = 0; q < B; ++q)
    _mm256_storeu_ps(score + 8 * (b + q), sum[q]);
}

// The forest as the AVX2 scoring reads it.
struct AvxForest {
  const std::array<std::size_t, kSlipFeatures + 1>& begin;
  const float* ascending;
  const std::uint8_t* feature;
  const std::int8_t* rank;
  const float* leaf;
  std::size_t trees;
  float base;
};

// The same scores in AVX2 for trees of depth D, compiled by function attribute only (the build
// has no -mavx2) and used only where the processor has it. Three passes over the frame's
// elements, 32 at a time in bytes where they can be:
//   1. each signal's count of thresholds below each element's value (8 floats per comparison);
//   2. each tree's leaf index from the counts (32 elements per comparison);
//   3. each element's leaves summed tree by tree, as score() (8 elements per gather).
template <std::size_t D>
TACTILE_AVX2 void score_avx2_depth(const AvxForest& f, const SlipColumns& columns, std::size_t n,
                                   float* score) noexcept {
  static_assert(kMaxSlipElements % 32 == 0);
  const std::size_t halves = (n + 31) / 32;  // of 32 elements; the columns hold 64
  alignas(32) std::int8_t count[kSlipFeatures][kMaxSlipElements];
  for (std::size_t h = 0; h < halves; ++h) {
    switch (std::min<std::size_t>((n - 32 * h + 7) / 8, 4)) {
      case 1:
        count_thresholds_avx2<1>(columns, 32 * h, f.begin, f.ascending, count);
        break;
      case 2:
        count_thresholds_avx2<2>(columns, 32 * h, f.begin, f.ascending, count);
        break;
      case 3:
        count_thresholds_avx2<3>(columns, 32 * h, f.begin, f.ascending, count);
        break;
      default:
        count_thresholds_avx2<4>(columns, 32 * h, f.begin, f.ascending, count);
        break;
    }
  }
  // Passes 2 and 3 by chunks of trees.
  alignas(32) std::uint8_t leaf[kTreeChunk][kMaxSlipElements];
  const std::size_t blocks = (n + 7) / 8;
  for (std::size_t b = 0; b < blocks; ++b)
    _mm256_storeu_ps(score + 8 * b, _mm256_set1_ps(f.base));
  for (std::size_t first = 0; first < f.trees; first += kTreeChunk) {
    const std::size_t trees = std::min(kTreeChunk, f.trees - first);
    for (std::size_t t = 0; t < trees; ++t) {
      const std::uint8_t* feature = f.feature + (first + t) * D;
      const std::int8_t* rank = f.rank + (first + t) * D;
      for (std::size_t h = 0; h < halves; ++h) {
        // Bit d of the index is split d's answer: from the last split to the first, the index
        // doubles and the answer (all ones, -1, when true) is subtracted.
        __m256i index = _mm256_setzero_si256();
        for (std::size_t d = D; d-- > 0;) {
          const __m256i c =
              _mm256_load_si256(reinterpret_cast<const __m256i*>(count[feature[d]] + 32 * h));
          const __m256i above = _mm256_cmpgt_epi8(c, _mm256_set1_epi8(rank[d]));
          index = _mm256_sub_epi8(_mm256_add_epi8(index, index), above);
        }
        _mm256_store_si256(reinterpret_cast<__m256i*>(leaf[t] + 32 * h), index);
      }
    }
    const float* leaves = f.leaf + (first << D);
    std::size_t b = 0;
    for (; b + 4 <= blocks; b += 4)
      sum_leaves_avx2<4, D>(leaf, leaves, trees, b, score);
    switch (blocks - b) {
      case 3:
        sum_leaves_avx2<3, D>(leaf, leaves, trees, b, score);
        break;
      case 2:
        sum_leaves_avx2<2, D>(leaf, leaves, trees, b, score);
        break;
      case 1:
        sum_leaves_avx2<1, D>(leaf, leaves, trees, b, score);
        break;
      default:
        break;
    }
  }
}

}  // namespace

TACTILE_AVX2 void ObliviousForest::score_avx2(const SlipColumns& columns, std::size_t n,
                                              float* score) const noexcept {
  const AvxForest f{begin_,       ascending_.data(), feature_.data(),          rank_.data(),
                    leaf_.data(), trees(),           static_cast<float>(base_)};
  switch (depth_) {
    case 1:
      return score_avx2_depth<1>(f, columns, n, score);
    case 2:
      return score_avx2_depth<2>(f, columns, n, score);
    case 3:
      return score_avx2_depth<3>(f, columns, n, score);
    case 4:
      return score_avx2_depth<4>(f, columns, n, score);
    case 5:
      return score_avx2_depth<5>(f, columns, n, score);
    case 6:
      return score_avx2_depth<6>(f, columns, n, score);
    case 7:
      return score_avx2_depth<7>(f, columns, n, score);
    default:
      return score_avx2_depth<8>(f, columns, n, score);
  }
}
#endif

void ObliviousForest::score_columns(const SlipColumns& columns, std::size_t n,
                                    std::array<float, kMaxSlipElements>& score,
                                    ModelScoring scoring) const noexcept {
  n = std::min(n, kMaxSlipElements);
#ifdef TACTILE_AVX2
  if (scoring == ModelScoring::kVector && kHasAvx2 && ranks_fit_ && trees() > 0) {
    score_avx2(columns, n, score.data());
    return;
  }
#else
  (void)scoring;
#endif
  score_portable(columns, n, score.data());
}

const char* ObliviousForest::vector_scoring() const noexcept {
  return kHasAvx2 && ranks_fit_ ? "avx2" : "portable";
}

}  // namespace tactile::control
