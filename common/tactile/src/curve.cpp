#include "tactile/curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace tactile {

PiecewiseLinear::PiecewiseLinear(std::vector<double> x, std::vector<double> y)
    : x_(std::move(x)), y_(std::move(y)) {}

double PiecewiseLinear::operator()(double x) const noexcept {
  const std::size_t n = std::min(x_.size(), y_.size());
  if (n == 0) return 0.0;
  if (n == 1) return y_[0];
  // Segment k covers [x_k, x_{k+1}]; the outer segments extend to infinity both ways.
  const auto it = std::upper_bound(x_.begin(), x_.begin() + static_cast<std::ptrdiff_t>(n), x);
  std::size_t k = static_cast<std::size_t>(it - x_.begin());
  k = std::clamp<std::size_t>(k, 1, n - 1) - 1;
  const double dx = x_[k + 1] - x_[k];
  const double slope = dx > 0.0 ? (y_[k + 1] - y_[k]) / dx : 0.0;
  const double v = y_[k] + slope * (x - x_[k]);
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
