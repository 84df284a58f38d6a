#pragma once

#include <algorithm>
#include <cmath>

#include "tactile/geometry.hpp"

namespace tactile {

// Calls f(y, x_begin, x_end) for every image row that holds pixel centres of the disk, where
// [x_begin, x_end) are the columns whose centres lie at most `radius` from `center`. Rows and
// columns are not clipped to any image.
template <typename F>
void for_each_disk_row(Vec2 center, double radius, F&& f) {
  const double r2 = radius * radius;
  const int y_lo = static_cast<int>(std::ceil(center.y - radius));
  const int y_hi = static_cast<int>(std::floor(center.y + radius));
  for (int y = y_lo; y <= y_hi; ++y) {
    const double dy = y - center.y;
    const double h2 = r2 - dy * dy;
    if (h2 < 0) continue;
    const double h = std::sqrt(h2);
    int x0 = static_cast<int>(std::ceil(center.x - h));
    int x1 = static_cast<int>(std::floor(center.x + h));
    // Guard the boundary against rounding: a centre exactly on the circle belongs to S.
    while ((x0 - 1 - center.x) * (x0 - 1 - center.x) + dy * dy <= r2)
      --x0;
    while ((x0 - center.x) * (x0 - center.x) + dy * dy > r2 && x0 <= x1)
      ++x0;
    while ((x1 + 1 - center.x) * (x1 + 1 - center.x) + dy * dy <= r2)
      ++x1;
    while ((x1 - center.x) * (x1 - center.x) + dy * dy > r2 && x1 >= x0)
      --x1;
    if (x1 >= x0) f(y, x0, x1 + 1);
  }
}

}  // namespace tactile
