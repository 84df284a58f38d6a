#pragma once

// Tick placement for plot axes: "nice" values a reader takes in at a glance.
#include <string>
#include <vector>

namespace tactile::plot {

// Ticks of a linear axis over [lo, hi]: every multiple of one step inside the range, the step
// being 1, 2 or 5 times a power of ten chosen so that about `target` ticks fall inside (never
// fewer than 2 for a non-empty range). lo > hi is treated as [hi, lo]; a range that is empty
// (lo == hi) or not finite gives no ticks. Values within a millionth of a step of zero are 0.
std::vector<double> linear_ticks(double lo, double hi, int target = 6);

// The step linear_ticks uses for [lo, hi]; 0 when it would give no ticks.
double linear_tick_step(double lo, double hi, int target = 6);

// Ticks of a logarithmic axis over [lo, hi] (both > 0): the powers of ten inside the range
// (every k-th one when there are more than about 10); where fewer than 3 powers of ten fall
// inside, 2 and 5 times each power of ten as well; where even that gives fewer than 2 ticks,
// linear ticks over the range. Non-positive or non-finite bounds give no ticks.
std::vector<double> log_ticks(double lo, double hi);

// Text for a tick value: as few decimals as tell the ticks of `step` apart, no trailing
// zeros, "-0" written as "0"; magnitudes of 1e5 and above or below 1e-3 in the form "2e-05"
// -> "2e-5" (mantissa and exponent, no "+" and no leading zeros in the exponent).
// step <= 0 means "the value alone" (used for log ticks).
std::string format_tick(double value, double step = 0);

}  // namespace tactile::plot
