#include "tactile/curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace tactile {

PiecewiseLinear::PiecewiseLinear(std::vector<double> x, std::vector<double> y)
    : x_(std::move(x)), y_(std::move(y)) {
  const std::size_t n = std::min(x_.size(), y_.size());
  slope_.assign(n > 1 ? n - 1 : 0, 0.0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double dx = x_[k + 1] - x_[k];
    slope_[k] = dx > 0.0 ? (y_[k + 1] - y_[k]) / dx : 0.0;
  }
}

double PiecewiseLinear::operator()(double x) const noexcept {
  if (slope_.empty()) return y_.empty() || x_.empty() ? 0.0 : y_[0];
  const std::size_t n = slope_.size() + 1;
  // Segment k covers [x_k, x_{k+1}]; the outer segments extend to infinity both ways: k is the
  // number of inner knots x_1 .. x_{n-2} at or below x, by a binary search without branches (x
  // jumps between segments from one call to the next, which defeats branch prediction).
  const double* const inner = x_.data() + 1;
  const double* base = inner;
  std::size_t len = n - 2;
  while (len > 1) {
    const std::size_t half = len / 2;
    base = base[half - 1] <= x ? base + half : base;
    len -= half;
  }
  const std::size_t k = static_cast<std::size_t>(base - inner) + (len == 1 && base[0] <= x ? 1 : 0);
  const double v = y_[k] + slope_[k] * (x - x_[k]);
  return std::isfinite(v) ? v : (v > 0 ? y_[n - 1] : y_[0]);
}

double PiecewiseLinear::inverse(double y) const noexcept {
  const std::size_t n = std::min(x_.size(), y_.size());
  if (n == 0) return 0.0;
  if (y <= y_[0] || n == 1) return x_[0];
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (y <= y_[k + 1]) {
      const double dy = y_[k + 1] - y_[k];
      if (dy <= 0.0) continue;  // flat stretch below y: keep looking
      return x_[k] + (y - y_[k]) * (x_[k + 1] - x_[k]) / dy;
    }
  }
  const double dy = y_[n - 1] - y_[n - 2];
  if (dy <= 0.0) return x_[n - 1];
  const double v = x_[n - 1] + (y - y_[n - 1]) * (x_[n - 1] - x_[n - 2]) / dy;
  return std::isfinite(v) ? v : std::numeric_limits<double>::max();
}

}  // namespace tactile
