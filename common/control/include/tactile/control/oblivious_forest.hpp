#pragma once

// The learned slip detector's model type (docs/slip.md, "The learned combiner"): gradient-boosted
// oblivious trees over the slip signals. Oblivious: every node of one depth of a tree splits on
// the same signal and threshold, so a tree of depth D is D comparisons ("x[feature] > threshold"
// sets bit d of the leaf's index) and a table of 2^D leaves.
//
// One type and one scoring for the model the controller runs (compiled in, slip_model.inc) and the
// model slip_train fits and chooses its decision level on: the score is the base plus each tree's
// leaf, summed in float tree by tree, by element (score) or by a frame's columns at once
// (score_columns, portable or AVX2), to the same bits every way. Built at start-up (the
// constructor allocates and throws); scoring allocates nothing and never throws.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "tactile/control/slip_signals.hpp"
#include "tactile/detail/multiversion.hpp"

namespace tactile::control {

// How a frame's elements are scored: with the processor's vector instructions where it has them
// (AVX2 on x86-64), or the portable loop. Both give ObliviousForest::score's scores exactly.
enum class ModelScoring : std::uint8_t { kVector, kPortable };

class ObliviousForest {
 public:
  // No trees: every score is 0.
  ObliviousForest() = default;
  // `feature`, `threshold`: per tree, `depth` splits; `leaf`: per tree, 2^depth values. Throws
  // std::invalid_argument when `features` is 0 or above kSlipFeatures, `depth` is outside 1..8, a
  // split's feature is not below `features`, a threshold is NaN or the sizes disagree.
  ObliviousForest(std::size_t features, std::size_t depth, double base,
                  std::vector<std::uint8_t> feature, std::vector<float> threshold,
                  std::vector<float> leaf);

  std::size_t features() const noexcept { return features_; }
  std::size_t depth() const noexcept { return depth_; }
  std::size_t trees() const noexcept { return depth_ == 0 ? 0 : feature_.size() / depth_; }
  double base() const noexcept { return base_; }
  std::span<const std::uint8_t> feature() const noexcept { return feature_; }
  std::span<const float> threshold() const noexcept { return threshold_; }
  std::span<const float> leaf() const noexcept { return leaf_; }

  // The score (log-odds of slip) of one element's `features()` values.
  float score(std::span<const float> x) const noexcept;
  // score() of the first `n` elements of `columns` at once, into score[0, n) (n is capped at
  // kMaxSlipElements). kVector falls back to the portable loop where the processor has no vector
  // path or the model does not fit it (a signal with more than 255 distinct thresholds).
  void score_columns(const SlipColumns& columns, std::size_t n,
                     std::array<float, kMaxSlipElements>& score,
                     ModelScoring scoring = ModelScoring::kVector) const noexcept;
  // The path kVector takes for this model: "avx2" or "portable".
  const char* vector_scoring() const noexcept;

 private:
  void score_portable(const SlipColumns& columns, std::size_t n, float* score) const noexcept;
#ifdef TACTILE_AVX2
  TACTILE_AVX2 void score_avx2(const SlipColumns& columns, std::size_t n,
                               float* score) const noexcept;
#endif

  std::size_t features_ = 0;
  std::size_t depth_ = 0;
  double base_ = 0;
  std::vector<std::uint8_t> feature_;
  std::vector<float> threshold_;
  std::vector<float> leaf_;
  // The thresholds by signal, for the vector path: each signal's distinct thresholds in ascending
  // order, ascending_[begin_[k], begin_[k + 1]), and each split's rank among its signal's, minus
  // 128. With an element's count of a signal's thresholds below its value, `value > threshold` of
  // the split is `count > rank`, exactly (the thresholds below a value are the first `count`; NaN
  // is below none, as for `>`).
  std::array<std::size_t, kSlipFeatures + 1> begin_{};
  std::vector<float> ascending_;
  std::vector<std::int8_t> rank_;
  bool ranks_fit_ = false;  // every signal has at most 255 thresholds
};

}  // namespace tactile::control
