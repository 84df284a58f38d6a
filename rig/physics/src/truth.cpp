#include "tactile/rig/truth.hpp"

#include <cmath>

namespace tactile::rig {

const GroundTruth& TruthRecorder::take(World& world, std::uint64_t frame_id,
                                       double slip_threshold_mm) {
  const double t = world.time();
  truth_.sim_time_s = t;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    const Fingertip& tip = world.fingertip(i);
    FingertipTruth& ft = truth_.fingertips[i];
    ft.camera_frame_id = frame_id;
    ft.camera_timestamp_ns = std::llround(t * 1e9);
    for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
      const Element& e = tip.elements[k];
      ElementTruth& et = ft.elements[k];
      const bool was_visible = et.visible;
      const bool was_sliding = et.sliding;
      et.id = static_cast<std::uint32_t>(k);
      et.contact = e.contact;
      et.fz_n = e.contact ? e.fn_n : 0.0;
      et.visible = e.contact && et.fz_n >= visible_fz_n_;
      et.fx_n = e.contact ? e.ft_n[0] : 0.0;
      et.fy_n = e.contact ? e.ft_n[1] : 0.0;
      et.ux_mm = e.contact ? e.s_mm[0] : 0.0;
      et.uy_mm = e.contact ? e.s_mm[1] : 0.0;
      et.releases = e.frame_releases;
      et.slip_mm = e.frame_slip_mm;
      et.surface_mm = std::hypot(e.frame_surface_mm[0], e.frame_surface_mm[1]);
      const double limit = world.params().cap.friction * e.fn_n;
      et.load_ratio = e.contact && limit > 0 ? std::hypot(et.fx_n, et.fy_n) / limit : 0.0;
      const bool moving = et.surface_mm > slip_threshold_mm;
      et.sliding = et.visible && was_visible &&
                   (et.slip_mm > slip_threshold_mm ||
                    (moving && (was_sliding || et.load_ratio >= partial_slip_ratio_)));
    }
  }
  const CapState& cap = world.cap();
  truth_.object_position_m = cap.position_m;
  truth_.cap_yaw_rad = cap.yaw_rad;
  truth_.cap_angle_deg = cap.angle_deg;
  truth_.cap_tight = cap.tight;
  truth_.dropped = cap.dropped;
  truth_.place = cap.place;
  truth_.cap_on_bottle = cap.place == CapPlace::kOnBottle || cap.place == CapPlace::kThreaded;
  world.clear_frame_accumulators();
  return truth_;
}

}  // namespace tactile::rig
