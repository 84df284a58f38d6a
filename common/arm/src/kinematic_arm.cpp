#include "tactile/arm/kinematic_arm.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tactile::arm {
namespace {

// Moves `from` toward `to` by at most `step`; true once there.
bool approach(double& from, double to, double step) {
  const double left = to - from;
  if (std::abs(left) <= step) {
    from = to;
    return true;
  }
  from += std::copysign(step, left);
  return false;
}

}  // namespace

KinematicArm::KinematicArm(const KinematicArmOptions& o, std::int64_t start_ns)
    : options_(o), now_ns_(start_ns) {
  if (!std::isfinite(o.finger_min_m) || !std::isfinite(o.finger_open_m) ||
      !std::isfinite(o.finger_max_m) || o.finger_min_m < 0 || o.finger_open_m < o.finger_min_m ||
      o.finger_max_m < o.finger_open_m) {
    throw std::invalid_argument("kinematic arm: the finger stroke must be 0 <= min <= open <= max");
  }
  state_.time_ns = start_ns;
  state_.wrist = o.start;
  state_.fingertip_position_m = {Vec3{-o.finger_open_m, 0, 0}, Vec3{o.finger_open_m, 0, 0}};
}

void KinematicArm::advance_to(std::int64_t now_ns) {
  if (now_ns <= now_ns_) return;
  const double dt = static_cast<double>(now_ns - now_ns_) * 1e-9;
  now_ns_ = now_ns;
  state_.time_ns = now_ns;
  if (moving_) {
    Vec3& p = state_.wrist.position_m;
    const Vec3 r = move_.target.position_m - p;
    const double dist = norm(r);
    const double step = move_.max_speed_mps * dt;
    const bool there = dist <= step;
    p = there ? move_.target.position_m : p + (step / dist) * r;
    const bool turned =
        approach(state_.wrist.yaw_rad, move_.target.yaw_rad, move_.max_yaw_rate_rps * dt);
    if (there && turned) {
      moving_ = false;
      state_.segment_done = true;
    }
  }
  state_.limit = false;
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    Vec3& p = state_.fingertip_position_m[i];
    Vec3 v_f = finger_velocity_f_[i];
    if (opening_) {
      // The last step of an open ends exactly at its distance.
      const double travel = std::min(open_left_m_[i], -v_f.z * dt);
      open_left_m_[i] -= travel;
      p = p - travel * kFingertipAxesInWrist[i].z;
      if (open_left_m_[i] <= 0) finger_velocity_f_[i] = v_f = {};
    } else {
      p = p + dt * in_wrist(kFingertipAxesInWrist[i], v_f);
    }
    // Within the stroke along the closing axis: at an end the finger stops (LIMIT).
    const double side = i == 0 ? -1.0 : 1.0;
    const double along = side * p.x;
    if (along < options_.finger_min_m || along > options_.finger_max_m) {
      p.x = side * std::clamp(along, options_.finger_min_m, options_.finger_max_m);
      finger_velocity_f_[i].z = 0;
      v_f.z = 0;
      state_.limit = true;
    }
    state_.fingertip_velocity_mps[i] = v_f;
  }
  if (opening_ && open_left_m_[0] <= 0 && open_left_m_[1] <= 0) opening_ = false;
}

void KinematicArm::stop_motion() {
  moving_ = false;
  opening_ = false;
  finger_velocity_f_ = {};
  state_.fingertip_velocity_mps = {};
  state_.holding = true;
}

wire::ArmStateData KinematicArm::read(std::int64_t now_ns) {
  advance_to(now_ns);
  return state_;
}

bool KinematicArm::write(const wire::ReceivedCommand& command, std::int64_t now_ns) {
  advance_to(now_ns);
  const control::Command& c = command.command;
  switch (c.kind) {
    case control::CommandKind::kMoveTo:
      move_ = c.move_to;
      moving_ = true;
      stopped_ = false;
      state_.holding = false;
      state_.active_segment_id = c.move_to.segment_id;
      state_.segment_done = false;
      if (!c.move_to.keep_finger_velocities) {
        opening_ = false;
        finger_velocity_f_ = {};
      }
      advance_to(now_ns);  // a target already reached is done at once
      return true;
    case control::CommandKind::kFingerVelocities:
      if (stopped_) return false;  // after Stop only a new segment moves the arm
      opening_ = false;
      finger_velocity_f_ = c.finger_velocities.velocity_mps;
      state_.holding = false;
      return true;
    case control::CommandKind::kOpen:
      if (stopped_) return false;
      opening_ = true;
      open_left_m_.fill(c.open.distance_m);
      finger_velocity_f_.fill({0, 0, -c.open.speed_mps});
      state_.holding = false;
      return true;
    case control::CommandKind::kHold:
      stop_motion();
      return true;
    case control::CommandKind::kStop:
      stop_motion();
      stopped_ = true;
      return true;
    case control::CommandKind::kNone:
      return false;
  }
  return false;
}

void KinematicArm::hold(std::int64_t now_ns) {
  advance_to(now_ns);
  stop_motion();
}

}  // namespace tactile::arm
