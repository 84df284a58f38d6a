// The learned detector's model type (docs/slip.md, "The learned combiner"): a forest scored by
// hand, every scoring path to the bit on forests of every depth (and one the vector path cannot
// hold), and the errors a bad forest is refused with.
#include "tactile/control/oblivious_forest.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "forest_paths.hpp"

namespace tactile::control {
namespace {

// Two trees of depth 2 on features 0 and 1 (of 2): tree 0 splits x0 > 0 (bit 0) and x1 > 1
// (bit 1); tree 1 splits x1 > -1 (bit 0) and x0 > 0 (bit 1).
ObliviousForest two_trees() {
  return ObliviousForest(2, 2, 0.5, {0, 1, 1, 0}, {0.0f, 1.0f, -1.0f, 0.0f},
                         {1, 2, 4, 8, 16, 32, 64, 128});
}

TEST(ObliviousForest, ScoresTheBasePlusEachTreesLeaf) {
  const ObliviousForest f = two_trees();
  EXPECT_EQ(f.trees(), 2U);
  struct Case {
    float x0, x1, score;
  };
  const Case cases[] = {
      {-1, -2, 0.5f + 1 + 16},  // tree 0 leaf 0; tree 1 leaf 0
      {1, -2, 0.5f + 2 + 64},   // leaf 1 (x0 > 0); leaf 2 (x0 > 0)
      {-1, 0, 0.5f + 1 + 32},   // leaf 0; leaf 1 (x1 > -1)
      {1, 2, 0.5f + 8 + 128},   // leaf 3; leaf 3
      {0, 1, 0.5f + 1 + 32},    // on the thresholds: not above
      {std::numeric_limits<float>::quiet_NaN(), 2, 0.5f + 4 + 32},  // NaN is above nothing
  };
  for (const Case& c : cases) {
    const float x[] = {c.x0, c.x1};
    EXPECT_EQ(f.score(x), c.score) << c.x0 << ", " << c.x1;
  }
  EXPECT_EQ(ObliviousForest().score(std::span<const float>()), 0.0f);
}

// A random forest of `trees` trees of `depth` on the first `signals` slip signals, its thresholds
// drawn from `distinct` values.
ObliviousForest random_forest(std::mt19937_64& rng, std::size_t trees, std::size_t depth,
                              int signals, int distinct) {
  std::uniform_int_distribution<int> signal(0, signals - 1), level(0, distinct - 1);
  std::normal_distribution<float> leaf(0.0f, 0.3f);
  std::vector<std::uint8_t> feature;
  std::vector<float> threshold, leaves;
  for (std::size_t s = 0; s < trees * depth; ++s) {
    feature.push_back(static_cast<std::uint8_t>(signal(rng)));
    threshold.push_back(static_cast<float>(level(rng)) / 9.0f - 1.0f);
  }
  for (std::size_t l = 0; l < trees << depth; ++l)
    leaves.push_back(leaf(rng));
  return ObliviousForest(kSlipFeatures, depth, -1.25, feature, threshold, leaves);
}

// The columns' values: on the thresholds, between and beyond them, infinite and NaN.
SlipColumns random_columns(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> kind(0, 5), step(-20, 600);
  SlipColumns columns{};
  for (auto& column : columns) {
    for (float& v : column) {
      switch (kind(rng)) {
        case 0:
          v = std::numeric_limits<float>::quiet_NaN();
          break;
        case 1:
          v = kind(rng) < 3 ? std::numeric_limits<float>::infinity()
                            : -std::numeric_limits<float>::infinity();
          break;
        case 2:
          v = static_cast<float>(step(rng)) / 9.0f - 1.0f + 0.01f;
          break;
        default:
          v = static_cast<float>(step(rng)) / 9.0f - 1.0f;
          break;
      }
    }
  }
  return columns;
}

TEST(ObliviousForest, EveryPathGivesTheRowScoresToTheBitAtEveryDepth) {
  std::mt19937_64 rng(3);
  std::size_t compared = 0;
  const int all = static_cast<int>(kSlipFeatures);
  // The last: about 700 distinct thresholds on one signal, more than the vector path's bytes
  // hold, so it falls back to the portable loop.
  for (const auto& [trees, depth, signals, distinct] : {std::tuple{1, 1, all, 5},
                                                        {3, 2, all, 40},
                                                        {70, 3, 4, 200},
                                                        {130, 5, all, 255},
                                                        {64, 7, all, 100},
                                                        {20, 8, 2, 60},
                                                        {200, 6, 1, 1000}}) {
    const ObliviousForest f = random_forest(rng, static_cast<std::size_t>(trees),
                                            static_cast<std::size_t>(depth), signals, distinct);
    for (int draw = 0; draw < 6; ++draw) {
      const SlipColumns columns = random_columns(rng);
      for (std::size_t n : {0, 1, 9, 31, 32, 41, 64}) {
        testing::expect_every_path_scores_exactly(
            f, columns, n, std::to_string(trees) + " trees of depth " + std::to_string(depth),
            compared);
        if (::testing::Test::HasFatalFailure()) return;
      }
    }
    if (distinct > 255) {
      EXPECT_STREQ(f.vector_scoring(), "portable");
    }
#ifdef TACTILE_AVX2
    if (distinct <= 255 && tactile::detail::cpu_has_avx2_fma()) {
      EXPECT_STREQ(f.vector_scoring(), "avx2");
    }
#endif
  }
  EXPECT_GT(compared, 5000U);
}

TEST(ObliviousForest, RefusesABadForestNamingWhatIsWrong) {
  const auto message = [](auto make) -> std::string {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(not refused)";
  };
  EXPECT_EQ(message([] { ObliviousForest(2, 0, 0, {}, {}, {}); }),
            "oblivious forest: depth must be 1..8, got 0");
  EXPECT_EQ(message([] { ObliviousForest(2, 9, 0, {}, {}, {}); }),
            "oblivious forest: depth must be 1..8, got 9");
  EXPECT_EQ(message([] {
              ObliviousForest(kSlipFeatures + 1, 1, 0, {0}, {0}, {0, 0});
            }),
            "oblivious forest: features must be 1.." + std::to_string(kSlipFeatures) + ", got " +
                std::to_string(kSlipFeatures + 1));
  EXPECT_EQ(message([] {
              ObliviousForest(2, 1, 0, {2}, {0}, {0, 0});
            }),
            "oblivious forest: split 0 is on feature 2 of 2");
  EXPECT_EQ(message([] {
              ObliviousForest(2, 2, 0, {0, 1}, {0, 0}, {0, 0, 0});
            }),
            "oblivious forest: per tree 2 splits and 4 leaves: got 2 features, 2 thresholds, 3 "
            "leaves");
  EXPECT_EQ(message([] {
              ObliviousForest(2, 1, 0, {0}, {std::numeric_limits<float>::quiet_NaN()}, {0, 0});
            }),
            "oblivious forest: split 0's threshold is NaN");
  EXPECT_EQ(message([] {
              ObliviousForest(2, 1, std::nan(""), {0}, {0}, {0, 0});
            }),
            "oblivious forest: the base score is not finite");
}

}  // namespace
}  // namespace tactile::control
