// One check for the tests of the model's scoring paths (oblivious_forest_test.cpp,
// slip_detector_test.cpp): the first `n` elements of `columns` scored at once by the vector path
// and by the portable loop give ObliviousForest::score's row scores to the bit.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>

#include "tactile/control/oblivious_forest.hpp"

namespace tactile::control::testing {

// Adds the elements compared to `compared`; `what` names the case in a failure.
inline void expect_every_path_scores_exactly(const ObliviousForest& forest,
                                             const SlipColumns& columns, std::size_t n,
                                             const std::string& what, std::size_t& compared) {
  std::array<float, kMaxSlipElements> vector{}, portable{};
  forest.score_columns(columns, n, vector, ModelScoring::kVector);
  forest.score_columns(columns, n, portable, ModelScoring::kPortable);
  for (std::size_t e = 0; e < n; ++e) {
    SlipFeatures x{};
    for (std::size_t k = 0; k < kSlipFeatures; ++k)
      x[k] = columns[k][e];
    const float expected = forest.score(x);
    ASSERT_EQ(std::bit_cast<std::uint32_t>(vector[e]), std::bit_cast<std::uint32_t>(expected))
        << what << ", " << n << " elements, element " << e << " (vector)";
    ASSERT_EQ(std::bit_cast<std::uint32_t>(portable[e]), std::bit_cast<std::uint32_t>(expected))
        << what << ", " << n << " elements, element " << e << " (portable)";
    ++compared;
  }
}

}  // namespace tactile::control::testing
