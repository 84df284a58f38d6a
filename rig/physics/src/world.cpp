#include "tactile/rig/world.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tactile::rig {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMmPerM = 1000.0;

Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

Vec3 rotate_yaw(Vec3 v, double c, double s) {
  return {c * v.x - s * v.y, s * v.x + c * v.y, v.z};
}

Vec3 rotate_yaw(Vec3 v, double yaw) {
  return rotate_yaw(v, std::cos(yaw), std::sin(yaw));
}

// hypot(a, b) > limit, with hypot only where the squares cannot decide: far from the limit the
// squares' rounding (a few ulps) cannot change the answer, near it the direct form does.
bool hypot_exceeds(double a, double b, double limit) {
  const double s2 = a * a + b * b;
  const double l2 = limit * limit;
  if (limit >= 0 && s2 < l2 * (1.0 - 1e-9)) return false;
  return std::hypot(a, b) > limit;
}

// hypot(a, b) <= max(0, limit - hypot(c, d)) certainly, from the squares' roots: each within a
// few ulps of its hypot (no underflow for a limit this far above it), so with a margin of 1e-9 of
// the limit the direct forms decide the same. False where the roots cannot tell (the caller then
// takes the direct forms).
bool surely_within(double a, double b, double c, double d, double limit) {
  return limit > 1e-100 &&
         std::sqrt(a * a + b * b) + std::sqrt(c * c + d * d) < limit * (1.0 - 1e-9);
}

// Margin of the fingertips' bounding test (m): far above the rounding of a feeler's position.
constexpr double kReachMargin = 1e-6;

Vec3 clamp_norm(Vec3 v, double max) {
  const double n = norm(v);
  return n > max && n > 0 ? (max / n) * v : v;
}

// 1-D bounded-acceleration approach of a target: the speed that still stops in time, changed
// by at most a*dt per step.
double approach_1d(double remaining, double v, double v_max, double a, double dt) {
  const double stop_speed = std::sqrt(2.0 * a * std::abs(remaining));
  const double v_des = std::copysign(std::min(v_max, stop_speed), remaining);
  return v + std::clamp(v_des - v, -a * dt, a * dt);
}

bool finite(Vec3 v) {
  return is_finite(v);
}

}  // namespace

const char* to_string(CapPlace p) {
  switch (p) {
    case CapPlace::kOnTable:
      return "on_table";
    case CapPlace::kFree:
      return "free";
    case CapPlace::kOnBottle:
      return "on_bottle";
    case CapPlace::kThreaded:
      return "threaded";
  }
  return "?";
}

World::World(const WorldParams& p) : p_(p) {
  mu_k_ = p_.cap.kinetic_ratio * p_.cap.friction;
  arm_.position_m = p_.arm.start_position_m;
  arm_.yaw_rad = p_.arm.start_yaw_rad;
  move_.target_position_m = arm_.position_m;
  move_.target_yaw_rad = arm_.yaw_rad;

  // Element layout on the dome: ring k holds 1, 8, 16, 16 elements at the given polar angle;
  // the last ring is turned by half a step so that its feelers sit between those of ring 2.
  constexpr std::array<int, 4> kCount{1, 8, 16, 16};
  constexpr std::array<double, 4> kTurn{0.0, 0.0, 0.0, 0.5};
  const double rd = p_.fingertip.dome_radius_m;
  std::array<Element, kElementsPerFingertip> layout{};
  std::size_t n = 0;
  for (std::size_t ring = 0; ring < kCount.size(); ++ring) {
    const double theta = p_.fingertip.ring_polar_deg[ring] * kPi / 180.0;
    for (int k = 0; k < kCount[ring]; ++k) {
      const double phi = 2.0 * kPi * (k + kTurn[ring]) / kCount[ring];
      Element& e = layout[n++];
      e.normal_f = {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                    std::cos(theta)};
      e.tip_f = {rd * e.normal_f.x, rd * e.normal_f.y, -rd * (1.0 - std::cos(theta))};
    }
  }
  const double open = p_.cap.radius_m + p_.arm.finger_open_m;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    tips_[i].elements = layout;
    tips_[i].offset_w = {i == 0 ? -open : open, 0, 0};
  }
  for (const Element& e : layout)
    reach_m_ = std::max(reach_m_, norm(e.tip_f));
  cap_.position_m = {p_.cap.x_m, p_.cap.y_m, p_.cap.height_m / 2.0};
  cap_.place = CapPlace::kOnTable;
  place_fingertips();
}

std::array<Vec3, kElementsPerFingertip> World::element_normals() const {
  std::array<Vec3, kElementsPerFingertip> out{};
  for (std::size_t k = 0; k < kElementsPerFingertip; ++k)
    out[k] = tips_[0].elements[k].normal_f;
  return out;
}

namespace {

// The integral over [0, u] of a profile that rises linearly from 0 to 1 over `ramp` and then
// stays at 1 (ramp 0: a step).
double ramp_integral(double u, double ramp) {
  if (u <= 0) return 0;
  if (ramp <= 0) return u;
  return u < ramp ? 0.5 * u * u / ramp : u - 0.5 * ramp;
}

// The profile's integral over [t0, t1] within its pulse [start, start + duration].
double pulse_integral(double start, double duration, double ramp, double t0, double t1) {
  if (!std::isfinite(start)) return 0;  // its stage has not begun
  const double a = std::max(t0, start);
  const double b = std::min(t1, start + duration);
  if (!(b > a)) return 0;
  return ramp_integral(b - start, ramp) - ramp_integral(a - start, ramp);
}

}  // namespace

Vec3 external_impulse_ns(const DisturbanceParams& d, double t0_s, double t1_s) {
  Vec3 j{};
  const PullParams& pull = d.pull;
  if (pull.force_n > 0) {
    j = j +
        (pull.force_n * pulse_integral(pull.start_s, pull.duration_s, pull.ramp_s, t0_s, t1_s)) *
            pull.direction;
  }
  const KnockParams& knock = d.knock;
  if (knock.impulse_ns > 0 && knock.duration_s > 0) {
    const double force = knock.impulse_ns / knock.duration_s;
    j = j +
        (force * pulse_integral(knock.start_s, knock.duration_s, 0, t0_s, t1_s)) * knock.direction;
  }
  return j;
}

double cap_mass_kg(const WorldParams& p, double t_s) {
  const MassStepParams& step = p.disturbance.mass_step;
  return step.added_kg > 0 && t_s >= step.start_s ? p.cap.mass_kg + step.added_kg : p.cap.mass_kg;
}

double grip_needed_n(const WorldParams& p, Vec3 accel_mps2, Vec3 squeeze_axis, double torque_nm,
                     double mass_kg, Vec3 external_force_n) {
  // What the fingers must apply to the cap: m (a - g) - F_ext, g pointing down.
  const double m = mass_kg;
  const Vec3 f = external_force_n;
  const Vec3 load{m * accel_mps2.x - f.x, m * accel_mps2.y - f.y,
                  m * (accel_mps2.z + p.gravity_mps2) - f.z};
  // Across the squeeze, horizontally: the direction the twist's couple acts in too.
  const Vec3 across = cross(Vec3{0, 0, 1}, squeeze_axis);
  const double vertical = 0.5 * load.z;
  const double horizontal = 0.5 * std::abs(dot(load, across));
  const double couple = std::abs(torque_nm) / (2.0 * p.cap.radius_m);
  // The fingertip whose couple adds to its horizontal share needs the most.
  return std::hypot(vertical, horizontal + couple) / p.cap.friction;
}

namespace {

// hold_need's grip at the peak acceleration along gravity: with the cap's own mass and no
// disturbance, grip_needed_n's; with disturbances, the largest of them (the mass after a mass
// step; the pull's or the knock's force, its vertical part adding to the load and its horizontal
// part across the squeeze, where the wrist may turn it).
double disturbed_grip_needed_n(const WorldParams& p, double peak_accel_mps2) {
  const DisturbanceParams& d = p.disturbance;
  const Vec3 accel{0, 0, peak_accel_mps2};
  const double m = p.cap.mass_kg + std::max(0.0, d.mass_step.added_kg);
  double need = grip_needed_n(p, accel, {1, 0, 0}, 0.0, m, {});
  const auto worst = [&](Vec3 force) {
    const Vec3 across{0, std::hypot(force.x, force.y), -std::abs(force.z)};
    need = std::max(need, grip_needed_n(p, accel, {1, 0, 0}, 0.0, m, across));
  };
  if (d.pull.force_n > 0) worst(d.pull.force_n * d.pull.direction);
  if (d.knock.impulse_ns > 0 && d.knock.duration_s > 0)
    worst((d.knock.impulse_ns / d.knock.duration_s) * d.knock.direction);
  return need;
}

}  // namespace

HoldNeed hold_need(const WorldParams& p, double f2_n) {
  HoldNeed h;
  const ArmParams& arm = p.arm;
  const double w = 2.0 * kPi * arm.vibration_hz;
  h.peak_accel_mps2 = arm.max_accel_mps2 + w * w * arm.vibration_m;
  h.grip_needed_n = disturbed_grip_needed_n(p, h.peak_accel_mps2);
  // The apex pressed in by F2 / k_n; each element's depth as contact_forces() takes it, with the
  // patch centred on the cap's height: along the squeeze its tip lies r_d (1 - cos theta) behind
  // the apex, across it r_d sin(theta) cos(phi), upward r_d sin(theta) sin(phi).
  const double kn = p.fingertip.normal_stiffness_npm;
  const double rc = p.cap.radius_m;
  const double half_h = p.cap.height_m / 2.0;
  const double apex_from_axis = rc - f2_n / kn;
  const World world(p);
  for (const Element& e : world.fingertip(0).elements) {
    const double across = e.tip_f.x;
    const double up = e.tip_f.y;
    const double depth_edge = std::clamp((half_h + 0.0005 - std::abs(up)) / 0.0005, 0.0, 1.0);
    const double depth = (rc - std::hypot(apex_from_axis - e.tip_f.z, across)) * depth_edge;
    if (depth > 0) h.grip_allowed_n += kn * depth;
  }
  h.holdable = h.grip_needed_n <= h.grip_allowed_n;
  return h;
}

bool World::apply(const ArmCommand& c) noexcept {
  if (!finite(c.target_position_m) || !std::isfinite(c.target_yaw_rad) ||
      !std::isfinite(c.max_speed_mps) || !std::isfinite(c.max_yaw_rate_rps) ||
      !std::isfinite(c.open_speed_mps) || !std::isfinite(c.open_distance_m) ||
      !finite(c.finger_velocity_mps[0]) || !finite(c.finger_velocity_mps[1])) {
    return false;
  }
  if (arm_.stopped) return c.kind == CommandKind::kNone;
  switch (c.kind) {
    case CommandKind::kNone:
      break;
    case CommandKind::kMoveTo:
      move_ = c;
      has_move_ = true;
      arm_.active_segment_id = c.segment_id;
      arm_.segment_done = false;
      arm_.holding = false;
      if (!c.keep_finger_velocities) {
        opening_ = false;
        for (auto& t : tips_)
          t.commanded_velocity_f = {};
      }
      break;
    case CommandKind::kFingerVelocities:
      opening_ = false;
      for (std::size_t i = 0; i < kFingertips; ++i)
        tips_[i].commanded_velocity_f = c.finger_velocity_mps[i];
      break;
    case CommandKind::kHold:
    case CommandKind::kStop:
      has_move_ = false;
      arm_.holding = true;
      arm_.stopped = c.kind == CommandKind::kStop;
      opening_ = false;
      for (auto& t : tips_)
        t.commanded_velocity_f = {};
      break;
    case CommandKind::kOpen:
      opening_ = true;
      open_speed_ = std::abs(c.open_speed_mps);
      open_left_m_.fill(std::abs(c.open_distance_m));
      for (auto& t : tips_)
        t.commanded_velocity_f = {0, 0, -open_speed_};
      break;
  }
  return true;
}

double World::cap_mass_kg() const noexcept {
  return rig::cap_mass_kg(p_, t_);
}

void World::start_disturbance(DisturbanceKind kind, double t_s) noexcept {
  DisturbanceParams& d = p_.disturbance;
  double& start = kind == DisturbanceKind::kPull       ? d.pull.start_s
                  : kind == DisturbanceKind::kMassStep ? d.mass_step.start_s
                                                       : d.knock.start_s;
  if (!std::isfinite(start) && std::isfinite(t_s)) start = t_s;
}

void World::add_external_force(Vec3& force, double dt) noexcept {
  external_force_n_ = (1.0 / dt) * external_impulse_ns(p_.disturbance, t_, t_ + dt);
  force = force + external_force_n_;
}

Vec3 World::wrist_accel_actual() const noexcept {
  const double w = 2.0 * kPi * p_.arm.vibration_hz;
  return arm_.accel_mps2 + (-w * w) * arm_.vibration_m;
}

void World::update_arm(double dt) noexcept {
  const double a = p_.arm.max_accel_mps2;
  const Vec3 velocity_before = arm_.velocity_mps;
  if (has_move_ && !arm_.segment_done) {
    const Vec3 r = move_.target_position_m - arm_.position_m;
    const double dist = norm(r);
    const double yaw_left = move_.target_yaw_rad - arm_.yaw_rad;
    // Arrived: close enough, and slow enough to stop within this step's acceleration bound.
    if (dist <= 1e-6 && norm(arm_.velocity_mps) <= a * dt && std::abs(yaw_left) <= 1e-5 &&
        std::abs(arm_.yaw_rate_rps) <= p_.arm.max_yaw_accel_rps2 * dt) {
      arm_.position_m = move_.target_position_m;
      arm_.yaw_rad = move_.target_yaw_rad;
      arm_.velocity_mps = {};
      arm_.yaw_rate_rps = 0;
      arm_.segment_done = true;
    } else {
      Vec3 v_des{};
      if (dist > 0) {
        const double speed = std::min(move_.max_speed_mps, std::sqrt(2.0 * a * dist));
        v_des = (speed / dist) * r;
      }
      arm_.velocity_mps = arm_.velocity_mps + clamp_norm(v_des - arm_.velocity_mps, a * dt);
      arm_.yaw_rate_rps = approach_1d(yaw_left, arm_.yaw_rate_rps, move_.max_yaw_rate_rps,
                                      p_.arm.max_yaw_accel_rps2, dt);
      arm_.position_m = arm_.position_m + dt * arm_.velocity_mps;
      arm_.yaw_rad += dt * arm_.yaw_rate_rps;
    }
  } else {
    // Hold, Stop or no segment: brake to rest.
    arm_.velocity_mps =
        arm_.velocity_mps + clamp_norm(-1.0 * arm_.velocity_mps, p_.arm.stop_decel_mps2 * dt);
    arm_.yaw_rate_rps =
        arm_.yaw_rate_rps + std::clamp(-arm_.yaw_rate_rps, -p_.arm.max_yaw_accel_rps2 * dt,
                                       p_.arm.max_yaw_accel_rps2 * dt);
    arm_.position_m = arm_.position_m + dt * arm_.velocity_mps;
    arm_.yaw_rad += dt * arm_.yaw_rate_rps;
  }
  arm_.accel_mps2 = (1.0 / dt) * (arm_.velocity_mps - velocity_before);
  // Vibration of the arm's servos: it grows while the arm moves and fades when it rests.
  // The arm's big joints shake in proportion to the speed they translate at; turning the
  // wrist alone does not.
  const double target =
      std::min(1.0, norm(arm_.velocity_mps) / std::max(p_.arm.vibration_full_speed_mps, 1e-6));
  // It builds up over vibration_rise_s; once the arm brakes, the held servos damp the mode
  // critically, within 1 / (2 pi f).
  const double fade = p_.arm.vibration_hz > 0 ? 1.0 / (2.0 * kPi * p_.arm.vibration_hz) : dt;
  const double tau =
      std::max(target >= arm_.vibration_envelope ? p_.arm.vibration_rise_s
                                                 : std::min(p_.arm.vibration_rise_s, fade),
               dt);
  arm_.vibration_envelope += (target - arm_.vibration_envelope) * (dt / tau);
  const double phase = 2.0 * kPi * p_.arm.vibration_hz * (t_ + dt);
  arm_.vibration_m = {0, 0, p_.arm.vibration_m * arm_.vibration_envelope * std::sin(phase)};
}

void World::update_fingers(double dt) noexcept {
  const double a = p_.arm.finger_accel_mps2;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    Fingertip& t = tips_[i];
    Vec3 target = t.commanded_velocity_f;
    if (opening_ && open_left_m_[i] <= 0) target = {};
    t.velocity_f = t.velocity_f + clamp_norm(target - t.velocity_f, a * dt);
    const FingertipAxes& ax = kFingertipAxesInWrist[i];
    const Vec3 v_w = in_wrist(ax, t.velocity_f);
    t.offset_w = t.offset_w + dt * v_w;
    if (opening_) open_left_m_[i] += dt * t.velocity_f.z;  // z_f velocity is negative
    // The fingertips cannot cross the grasp centre nor open beyond their stroke.
    const double side = i == 0 ? -1.0 : 1.0;
    const double along = side * t.offset_w.x;
    if (along < 0.001 || along > 0.06) {
      t.offset_w.x = side * std::clamp(along, 0.001, 0.06);
      t.velocity_f.z = 0;
    }
  }
}

void World::place_fingertips() noexcept {
  const Vec3 wrist = wrist_actual();
  const double c = std::cos(arm_.yaw_rad);
  const double s = std::sin(arm_.yaw_rad);
  for (std::size_t i = 0; i < kFingertips; ++i) {
    Fingertip& t = tips_[i];
    const FingertipAxes& ax = kFingertipAxesInWrist[i];
    t.x_f = rotate_yaw(ax.x, c, s);
    t.y_f = rotate_yaw(ax.y, c, s);
    t.z_f = rotate_yaw(ax.z, c, s);
    t.apex_world = wrist + rotate_yaw(t.offset_w, c, s);
  }
}

void World::release_to(Element& e, double force_n) const noexcept {
  // Scale the deflection along its own direction until |f(s)| equals force_n (bisection: a
  // release is a rare event, and f is monotonic).
  const double sx = e.s_mm[0];
  const double sy = e.s_mm[1];
  double lo = 0.0;
  double hi = 1.0;
  if (force_n > 0) {
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (lo + hi);
      const double f = std::hypot(shear_force(mid * sx), shear_force(mid * sy));
      (f > force_n ? hi : lo) = mid;
    }
  }
  e.s_mm = {lo * sx, lo * sy};
  e.ft_n = {shear_force(e.s_mm[0]), shear_force(e.s_mm[1])};
}

World::BaseMotion World::base_motion(double dt) const noexcept {
  BaseMotion b;
  b.wrist = wrist_actual();
  b.vibration_velocity = {0, 0,
                          p_.arm.vibration_m * arm_.vibration_envelope * 2.0 * kPi *
                              p_.arm.vibration_hz *
                              std::cos(2.0 * kPi * p_.arm.vibration_hz * (t_ + dt))};
  for (std::size_t i = 0; i < kFingertips; ++i) {
    const Fingertip& t = tips_[i];
    const FingertipAxes& ax = kFingertipAxesInWrist[i];
    b.finger_velocity[i] = rotate_yaw(in_wrist(ax, t.velocity_f), arm_.yaw_rad);
  }
  return b;
}

Vec3 World::relative_velocity(const BaseMotion& b, std::size_t i, Vec3 pe) const noexcept {
  const Vec3 z{0, 0, 1};
  const Vec3 v_surface = cap_.velocity_mps + cap_.yaw_rate_rps * cross(z, pe - cap_.position_m);
  const Vec3 v_base = arm_.velocity_mps + b.vibration_velocity +
                      arm_.yaw_rate_rps * cross(z, pe - b.wrist) + b.finger_velocity[i];
  return v_surface - v_base;
}

bool World::out_of_reach(const Fingertip& t) const noexcept {
  const Vec3 a = t.apex_world - cap_.position_m;
  const double reach = reach_m_ + kReachMargin;
  const double side = p_.cap.radius_m + reach;
  // Beyond the rim's 0.5 mm fade-out above or below, or beyond the cap's side.
  return std::abs(a.z) > p_.cap.height_m / 2.0 + 0.0005 + reach ||
         a.x * a.x + a.y * a.y > side * side;
}

void World::contact_forces(const BaseMotion& b, Vec3& force, double& torque, double dt) noexcept {
  const double rc = p_.cap.radius_m;
  const double half_h = p_.cap.height_m / 2.0;
  const double kn = p_.fingertip.normal_stiffness_npm;
  const double ct = p_.fingertip.tangential_damping_nspm;
  // Squared distances beyond this (rc with a margin over their rounding) are out of contact.
  const double rc2_out = rc * rc * (1.0 + 1e-9);
  const Vec3 c = cap_.position_m;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    Fingertip& t = tips_[i];
    // A fingertip away from the cap: its feelers are all out of contact, and were already.
    if (!touching_[i] && out_of_reach(t)) continue;
    bool touching = false;
    for (Element& e : t.elements) {
      const Vec3 pe = t.apex_world + e.tip_f.x * t.x_f + e.tip_f.y * t.y_f + e.tip_f.z * t.z_f;
      const double dx = pe.x - c.x;
      const double dy = pe.y - c.y;
      const double dz = pe.z - c.z;
      // The cap's rim: a feeler beyond the top or bottom edge loses contact over 0.5 mm.
      const double edge = std::clamp((half_h + 0.0005 - std::abs(dz)) / 0.0005, 0.0, 1.0);
      const double d2 = dx * dx + dy * dy;
      const double d = edge > 0 && d2 <= rc2_out ? std::hypot(dx, dy) : rc;
      const double depth = (rc - d) * edge;
      if (depth <= 0 || d <= 1e-9) {
        if (e.contact) {
          e.contact = false;
          e.indentation_m = 0;
          e.fn_n = 0;
          e.s_mm = {};
          e.ft_n = {};
          e.sliding = false;
        }
        continue;
      }
      touching = true;
      const bool sticking = e.contact && !e.sliding;
      const double rate = e.contact ? (depth - e.indentation_m) : 0.0;
      e.contact = true;
      e.indentation_m = depth;
      e.fn_n = kn * depth;
      const double fn_total = std::max(0.0, e.fn_n + p_.fingertip.normal_damping_nspm * rate / dt);
      const Vec3 inward{-dx / d, -dy / d, 0.0};
      Vec3 f = fn_total * inward;
      f = f - e.ft_n[0] * t.x_f - e.ft_n[1] * t.y_f;
      // The rubber of a sticking feeler is viscoelastic: it also resists the rate of its
      // deflection, c_t ds/dt. Without it the cap rings on the feelers' springs after every
      // change of load, undamped, and the heavier the cap the larger the ringing. Spring and
      // damper together stay inside the friction cone; past it the tip breaks loose
      // (update_tangential).
      if (sticking && ct > 0) {
        const Vec3 v_rel = relative_velocity(b, i, pe);
        const double fx = ct * dot(v_rel, t.x_f);
        const double fy = ct * dot(v_rel, t.y_f);
        const double cone = p_.cap.friction * e.fn_n;
        double scale = 1.0;
        if (!surely_within(fx, fy, e.ft_n[0], e.ft_n[1], cone)) {
          const double room = std::max(0.0, cone - std::hypot(e.ft_n[0], e.ft_n[1]));
          const double damping = std::hypot(fx, fy);
          scale = damping > room ? room / damping : 1.0;
        }
        f = f - (scale * fx) * t.x_f - (scale * fy) * t.y_f;
      }
      force = force + f;
      torque += dx * f.y - dy * f.x;
    }
    touching_[i] = touching;
  }
}

void World::update_tangential(const BaseMotion& b, double dt) noexcept {
  for (std::size_t i = 0; i < kFingertips; ++i) {
    if (!touching_[i]) continue;
    Fingertip& t = tips_[i];
    for (Element& e : t.elements) {
      if (!e.contact) continue;
      const Vec3 pe = t.apex_world + e.tip_f.x * t.x_f + e.tip_f.y * t.y_f + e.tip_f.z * t.z_f;
      const Vec3 v_rel = relative_velocity(b, i, pe);
      const double ds_x = dot(v_rel, t.x_f) * dt * kMmPerM;
      const double ds_y = dot(v_rel, t.y_f) * dt * kMmPerM;
      e.frame_surface_mm[0] += ds_x;
      e.frame_surface_mm[1] += ds_y;
      e.s_mm[0] += ds_x;
      e.s_mm[1] += ds_y;
      e.ft_n = {shear_force(e.s_mm[0]), shear_force(e.s_mm[1])};
      e.sliding = false;
      // Static friction holds the tip until the spring force reaches mu_s F_n; then the tip
      // breaks loose and the spring swings through the kinetic level to 2 mu_k - mu_s (the
      // undamped stick-slip release), where the tip sticks again.
      if (hypot_exceeds(e.ft_n[0], e.ft_n[1], p_.cap.friction * e.fn_n)) {
        const std::array<double, 2> before = e.s_mm;
        release_to(e, std::max(0.0, 2.0 * mu_k_ - p_.cap.friction) * e.fn_n);
        e.sliding = true;
        ++e.frame_releases;
        e.frame_slip_mm += std::hypot(before[0] - e.s_mm[0], before[1] - e.s_mm[1]);
      }
    }
  }
}

void World::update_cap_place() noexcept {
  const double bottom = cap_.position_m.z - p_.cap.height_m / 2.0;
  const double off_axis =
      std::hypot(cap_.position_m.x - bottle_x_m(), cap_.position_m.y - bottle_y_m());
  const bool any_contact = touching_[0] || touching_[1];

  if (bottom > 0.005) cap_.lifted = true;
  if (cap_.place == CapPlace::kThreaded) {
    const double sign = p_.bottle.tighten_clockwise ? -1.0 : 1.0;
    cap_.angle_deg = sign * (cap_.yaw_rad - cap_.seat_yaw_rad) * 180.0 / kPi;
    if (cap_.angle_deg > p_.bottle.free_turn_deg) cap_.tight = true;
    return;
  }
  const bool over_neck = off_axis < p_.cap.radius_m;
  if (over_neck && bottom <= p_.bottle.height_m + 1e-4 && bottom > p_.bottle.height_m - 0.003) {
    cap_.place = CapPlace::kOnBottle;
    // Let go on the neck, centred: the thread engages.
    if (!any_contact && off_axis < 0.001) {
      cap_.place = CapPlace::kThreaded;
      cap_.seat_yaw_rad = cap_.yaw_rad;
      cap_.angle_deg = 0;
    }
    return;
  }
  if (bottom <= 1e-4) {
    if (cap_.lifted && cap_.place != CapPlace::kOnTable) cap_.dropped = true;
    cap_.place = CapPlace::kOnTable;
    return;
  }
  cap_.place = CapPlace::kFree;
}

// Supports: the table top, and the bottle neck under a cap that meets it.
World::Supports World::support_forces(Vec3& force, double inertia) const noexcept {
  const double bottom = cap_.position_m.z - p_.cap.height_m / 2.0;
  const Vec3 to_axis{bottle_x_m() - cap_.position_m.x, bottle_y_m() - cap_.position_m.y, 0};
  const double off_axis = std::hypot(to_axis.x, to_axis.y);
  Supports s;
  if (bottom < 0) {
    s.table_n = std::max(
        0.0, -p_.table_stiffness_npm * bottom - p_.table_damping_nspm * cap_.velocity_mps.z);
    force.z += s.table_n;
    s.friction_torque_max = p_.cap.table_friction * s.table_n * (2.0 / 3.0) * p_.cap.radius_m;
  }
  if (p_.cap.held_to_table) {
    // The anchor: back to the resting place horizontally, down onto the table when pulled up.
    const double k = p_.table_stiffness_npm;
    const double c = p_.table_damping_nspm;
    force.x += -k * (cap_.position_m.x - p_.cap.x_m) - c * cap_.velocity_mps.x;
    force.y += -k * (cap_.position_m.y - p_.cap.y_m) - c * cap_.velocity_mps.y;
    if (bottom > 0) force.z += -k * bottom - c * cap_.velocity_mps.z;
  }
  const bool on_neck = cap_.place == CapPlace::kOnBottle || cap_.place == CapPlace::kThreaded ||
                       (off_axis < p_.cap.radius_m && bottom < p_.bottle.height_m &&
                        bottom > p_.bottle.height_m - 0.003);
  if (!on_neck) return s;
  const double pen = p_.bottle.height_m - bottom;
  double fz = p_.seat_stiffness_npm * pen - p_.seat_damping_nspm * cap_.velocity_mps.z;
  // Before the thread engages the neck only pushes; after, it holds the cap both ways.
  if (cap_.place != CapPlace::kThreaded) fz = std::max(0.0, fz);
  force.z += fz;
  if (off_axis < p_.bottle.capture_radius_m || cap_.place == CapPlace::kThreaded) {
    force.x += p_.seat_stiffness_npm * to_axis.x - p_.seat_damping_nspm * cap_.velocity_mps.x;
    force.y += p_.seat_stiffness_npm * to_axis.y - p_.seat_damping_nspm * cap_.velocity_mps.y;
  }
  if (cap_.place == CapPlace::kThreaded) {
    const double sign = p_.bottle.tighten_clockwise ? -1.0 : 1.0;
    const double over = cap_.angle_deg - p_.bottle.free_turn_deg;
    if (over > 0) {
      const double rate = sign * cap_.yaw_rate_rps;
      const double k = p_.bottle.tight_stiffness_nm_per_rad;
      const double damping = 2.0 * std::sqrt(k * inertia);
      s.thread_torque = -sign * (k * over * kPi / 180.0 + damping * std::max(rate, 0.0));
    }
    s.friction_torque_max += p_.bottle.free_torque_nm;
  }
  return s;
}

// Semi-implicit Euler; the table's and thread's Coulomb friction by the implicit regularised
// form: a viscous law stiff enough to hold, capped at the Coulomb value.
void World::integrate_cap(Vec3 force, double torque, const Supports& s, double inertia,
                          double dt) noexcept {
  const double m = cap_mass_kg();
  const double eps = p_.slip_speed_eps_mps;
  Vec3 v = cap_.velocity_mps + (dt / m) * force;
  if (s.table_n > 0) {
    const double c = p_.cap.table_friction * s.table_n / eps;
    const Vec3 vh{v.x, v.y, 0};
    const Vec3 vh_new = (1.0 / (1.0 + dt * c / m)) * vh;
    Vec3 fr = (m / dt) * (vh_new - vh);
    fr = clamp_norm(fr, p_.cap.table_friction * s.table_n);
    v = v + (dt / m) * fr;
  }
  double w = cap_.yaw_rate_rps + dt * torque / inertia;
  if (s.friction_torque_max > 0) {
    const double c = s.friction_torque_max * p_.cap.radius_m / eps;
    const double w_new = w / (1.0 + dt * c / inertia);
    const double tf =
        std::clamp((w_new - w) * inertia / dt, -s.friction_torque_max, s.friction_torque_max);
    w += dt * tf / inertia;
  }
  cap_.velocity_mps = v;
  cap_.yaw_rate_rps = w;
  cap_.position_m = cap_.position_m + dt * v;
  cap_.yaw_rad += dt * w;
  cap_.thread_torque_nm = s.thread_torque;
}

bool World::state_finite() const noexcept {
  const bool ok = finite(cap_.position_m) && finite(cap_.velocity_mps) &&
                  std::isfinite(cap_.yaw_rad) && std::isfinite(cap_.yaw_rate_rps) &&
                  finite(arm_.position_m);
  // 0 x a finite value is 0, 0 x inf or NaN is NaN: one sum tells whether all are finite,
  // without a branch per element.
  double zero = 0;
  for (const Fingertip& t : tips_) {
    for (const Element& e : t.elements)
      zero += 0.0 * e.fn_n + 0.0 * e.s_mm[0] + 0.0 * e.s_mm[1];
  }
  return ok && zero == 0;
}

// After a step that left something non-finite: the last finite state, every feeler let go.
void World::roll_back(const ArmState& arm, const CapState& cap, double dt) noexcept {
  arm_ = arm;
  cap_ = cap;
  for (Fingertip& t : tips_) {
    for (Element& e : t.elements) {
      e = Element{e.tip_f, e.normal_f};
    }
  }
  touching_ = {};
  place_fingertips();
  t_ -= dt;
}

bool World::step(double dt) noexcept {
  if (!(dt > 0) || !std::isfinite(dt)) return false;
  const ArmState arm_before = arm_;
  const CapState cap_before = cap_;

  update_arm(dt);
  update_fingers(dt);
  place_fingertips();

  const BaseMotion base = base_motion(dt);
  const double m = cap_mass_kg();
  Vec3 force{0, 0, -m * p_.gravity_mps2};
  add_external_force(force, dt);
  double torque = 0;
  contact_forces(base, force, torque, dt);
  const double inertia = p_.cap.inertia_factor * m * p_.cap.radius_m * p_.cap.radius_m;
  const Supports supports = support_forces(force, inertia);
  torque += supports.thread_torque;
  integrate_cap(force, torque, supports, inertia, dt);

  update_tangential(base, dt);
  update_cap_place();
  t_ += dt;

  if (state_finite()) return true;
  roll_back(arm_before, cap_before, dt);  // never seen
  return false;
}

void World::clear_frame_accumulators() noexcept {
  for (Fingertip& t : tips_) {
    for (Element& e : t.elements) {
      e.frame_releases = 0;
      e.frame_slip_mm = 0;
      e.frame_surface_mm = {};
    }
  }
}

}  // namespace tactile::rig
