#include "tactile/rig/truth.hpp"

#include <algorithm>
#include <cmath>

namespace tactile::rig {

GripTruth grip_truth(const World& world, const GroundTruth& truth) {
  const WorldParams& p = world.params();
  const CapState& cap = world.cap();
  GripTruth g;
  std::array<bool, kFingertips> touching{};
  for (std::size_t i = 0; i < kFingertips; ++i) {
    double slid = 0;
    for (const ElementTruth& et : truth.fingertips[i].elements) {
      if (!et.contact) continue;
      touching[i] = true;
      g.applied_n[i] += et.fz_n;
      slid += et.fz_n * et.slip_mm;
    }
    if (g.applied_n[i] > 0) g.slide_mm = std::max(g.slide_mm, slid / g.applied_n[i]);
  }
  // A cap anchored to the table (the sweep's cap_held case) rises by the anchor's stretch under a
  // firm pull and leaves the table's contact, but the anchor holds it, not the fingers.
  g.held = touching[0] && touching[1] && cap.place == CapPlace::kFree && !p.cap.held_to_table;
  const Vec3 a0 = world.fingertip(0).apex_world;
  const Vec3 a1 = world.fingertip(1).apex_world;
  const Vec3 squeeze{a1.x - a0.x, a1.y - a0.y, 0};  // horizontal: the wrist only turns
  const double gap = norm(squeeze);
  const Vec3 axis = gap > 0 ? (1.0 / gap) * squeeze : world.fingertip(0).z_f;
  // On the thread the fingers turn the cap against its friction and, past the free turn, its
  // rising torque.
  const double thread_nm = cap.place == CapPlace::kThreaded
                               ? p.bottle.free_torque_nm + std::abs(cap.thread_torque_nm)
                               : 0.0;
  g.needed_n = grip_needed_n(p, world.wrist_accel_actual(), axis, thread_nm, world.cap_mass_kg(),
                             world.external_force_n());
  return g;
}

void CrushTruth::add(double t_s, const GripTruth& grip) noexcept {
  const double applied = std::max(grip.applied_n[0], grip.applied_n[1]);
  peak_grip_n = std::max(peak_grip_n, applied);
  if (crush_force_n > 0 && !broken && applied > crush_force_n) {
    broken = true;
    broken_at_s = t_s;
  }
}

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
