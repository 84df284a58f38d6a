#pragma once

#include <span>
#include <vector>

namespace tactile {

// A piecewise-linear calibration curve y = c(x) through knots (x_i, y_i): x strictly increasing
// from 0, y non-decreasing from 0. Beyond the last knot it continues with the last segment's
// slope; below the first knot (x < 0) it continues with the first segment's slope.
class PiecewiseLinear {
 public:
  PiecewiseLinear() = default;
  PiecewiseLinear(std::vector<double> x, std::vector<double> y);

  // No allocation, no exceptions; a finite input gives a finite output.
  double operator()(double x) const noexcept;
  // The same extended with odd symmetry: c(-x) = -c(x) (the shear curve f).
  double odd(double x) const noexcept { return x < 0.0 ? -(*this)(-x) : (*this)(x); }
  // The smallest x >= 0 with c(x) = y, for y >= 0 (the rig's optics render through it).
  // Flat stretches answer their left end; y beyond the last knot extrapolates when the last
  // slope is positive and answers the last knot otherwise.
  double inverse(double y) const noexcept;

  std::span<const double> x() const { return x_; }
  std::span<const double> y() const { return y_; }
  bool empty() const { return x_.empty(); }

 private:
  std::vector<double> x_;
  std::vector<double> y_;
  std::vector<double> slope_;  // of each segment, 0 where it has no width
};

}  // namespace tactile
