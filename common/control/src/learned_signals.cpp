#include "learned_signals.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>

namespace tactile::control::learned {

ContactCounts count_contact(const FingertipInput& in, std::size_t count, const field::RigidFit& fit,
                            double thr) {
  ContactCounts c;
  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    if (!field::usable(r)) continue;
    c.total_fz_n += r.fz;
    if (!r.has_displacement) continue;
    ++c.measured;
    // Squared lengths against thr^2: a count, cheaper than a length.
    const double thr2 = thr * thr;
    if (r.dx_mm * r.dx_mm + r.dy_mm * r.dy_mm > thr2) ++c.moved;
    if (fit.rigid()) {
      const double ex = r.dx_mm - fit.at_x(r.y_px), ey = r.dy_mm - fit.at_y(r.x_px);
      if (ex * ex + ey * ey > thr2) ++c.departed;
    }
  }
  return c;
}

void write_fingertip_signals(const FingertipSignals& s, std::size_t n, SlipColumns& columns) {
  const ContactCounts& c = s.counts;
  const double inv = s.inv_threshold;
  const double values[] = {
      s.rigid_mm * inv,                                                        // rigid_dr
      s.arm.speed_mps * 1e3,                                                   // arm_speed_mmps
      s.arm.yaw_rate_rps * (180.0 / 3.14159265358979323846),                   // arm_yaw_dps
      c.measured > 0 ? static_cast<double>(c.moved) / c.measured : 0.0,        // share_moved
      c.measured > 0 ? static_cast<double>(c.departed) / c.measured : 0.0,     // share_departed
      c.total_fz_n,                                                            // total_fz_n
      (c.total_fz_n - s.last_total_fz_n) / std::max(s.last_total_fz_n, 0.01),  // total_dfz_rel
      static_cast<double>(c.measured),                                         // measured
      s.threshold_mm * 1e3,                                                    // dr_um
      s.mu,                                                                    // mu
      s.arm.speed_mps * 1e3 * s.period_s * inv,                                // arm_dr
      s.period_s > 0 ? 1.0 / s.period_s : 0.0,                                 // fps
      s.share_slipping,                                                        // share_slipping
      s.share_slipping_prev,  // share_slipping_prev
  };
  static_assert(std::size(values) == kFingertipSignals.size());
  for (std::size_t j = 0; j < kFingertipSignals.size(); ++j)
    std::fill_n(columns[column(kFingertipSignals[j])].begin(), n, finite_signal(values[j]));
}

}  // namespace tactile::control::learned
