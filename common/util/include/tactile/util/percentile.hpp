#pragma once

// The one percentile of the project (docs/architecture.md, rule 9): nearest rank. Of n values
// sorted ascending, the q-quantile is the value at rank ceil(q n), counted from 1 and at least 1:
// the smallest value with at least a fraction q of the values at or below it. Always one of the
// values, never an interpolation between two; q = 0.5 of an even count is the lower middle one.
// Every percentile in the rig's reports, the sweep's summary, slip_train's decision level and
// the benchmarks' tables is this one (docs/benchmarks.md). Pure: no I/O.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

namespace tactile::util {

// The q-quantile (0 <= q <= 1) of values already sorted ascending; `sorted` must not be empty.
inline double nearest_rank_of_sorted(std::span<const double> sorted, double q) {
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

// The q-quantile of `v` in any order; `if_empty` when it has no values.
inline double nearest_rank_percentile(std::vector<double> v, double q, double if_empty = 0.0) {
  if (v.empty()) return if_empty;
  std::sort(v.begin(), v.end());
  return nearest_rank_of_sorted(v, q);
}

}  // namespace tactile::util
