#include "tactile/control/config.hpp"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

namespace tactile::control {

const char* to_string(Task t) {
  switch (t) {
    case Task::kGraspMoveTwist:
      return "grasp_move_twist";
    case Task::kGraspMoveRelease:
      return "grasp_move_release";
    case Task::kTwistOnly:
      return "twist_only";
  }
  return "?";
}

const char* to_string(SlipDetectorKind k) {
  switch (k) {
    case SlipDetectorKind::kPaper:
      return "paper";
    case SlipDetectorKind::kField:
      return "field";
    case SlipDetectorKind::kLearned:
      return "learned";
  }
  return "?";
}

const char* to_string(GripKind k) {
  switch (k) {
    case GripKind::kPaper:
      return "paper";
    case GripKind::kMargin:
      return "margin";
  }
  return "?";
}

std::optional<GripKind> grip_from_string(std::string_view name) {
  for (auto k : {GripKind::kPaper, GripKind::kMargin}) {
    if (name == to_string(k)) return k;
  }
  return std::nullopt;
}

std::string describe_controller(const Config& c) {
  return std::string("slip detector: ") + to_string(c.slip_detector) +
         ", grip: " + to_string(c.grip);
}

std::optional<SlipDetectorKind> slip_detector_from_string(std::string_view name) {
  for (auto k : {SlipDetectorKind::kPaper, SlipDetectorKind::kField, SlipDetectorKind::kLearned}) {
    if (name == to_string(k)) return k;
  }
  return std::nullopt;
}

namespace {

template <typename T>
[[noreturn]] void fail(const char* field, T value, const char* rule) {
  std::ostringstream s;
  s << "control config: " << field << " = " << value << ": " << rule;
  throw std::invalid_argument(s.str());
}

void finite(const char* field, double v) {
  if (!std::isfinite(v)) fail(field, v, "must be finite");
}
void positive(const char* field, double v) {
  finite(field, v);
  if (!(v > 0)) fail(field, v, "must be > 0");
}
void non_negative(const char* field, double v) {
  finite(field, v);
  if (v < 0) fail(field, v, "must be >= 0");
}
void at_most(const char* field, double v, const char* bound_name, double bound) {
  if (v > bound) {
    const std::string rule = std::string("must be <= ") + bound_name;
    fail(field, v, rule.c_str());
  }
}

// The margin grip's parameters (checked whichever grip runs: a bad value is a bad file).
void validate_margin_grip(const Config& c) {
  positive("grip_touch_n", c.grip_touch_n);
  at_most("grip_touch_n", c.grip_touch_n, "f1_n", c.f1_n);
  positive("grip_min_n", c.grip_min_n);
  positive("grip_lift_n", c.grip_lift_n);
  if (c.grip_lift_n < c.grip_min_n) fail("grip_lift_n", c.grip_lift_n, "must be >= grip_min_n");
  if (!(c.grip_min_n > c.grip_touch_n)) fail("grip_min_n", c.grip_min_n, "must be > grip_touch_n");
  non_negative("grip_loading_speed_mps", c.grip_loading_speed_mps);
  at_most("grip_loading_speed_mps", c.grip_loading_speed_mps, "lift_speed_mps", c.lift_speed_mps);
  non_negative("grip_loading_distance_m", c.grip_loading_distance_m);
  at_most("grip_loading_distance_m", c.grip_loading_distance_m, "0.01", 0.01);
  non_negative("grip_margin", c.grip_margin);
  at_most("grip_margin", c.grip_margin, "2", 2.0);
  non_negative("grip_twist_margin", c.grip_twist_margin);
  at_most("grip_twist_margin", c.grip_twist_margin, "4", 4.0);
  positive("grip_mu_min", c.grip_mu_min);
  positive("grip_mu_max", c.grip_mu_max);
  if (!(c.grip_mu_max >= c.grip_mu_min))
    fail("grip_mu_max", c.grip_mu_max, "must be >= grip_mu_min");
  positive("grip_mu_initial", c.grip_mu_initial);
  if (c.grip_mu_initial < c.grip_mu_min || c.grip_mu_initial > c.grip_mu_max) {
    fail("grip_mu_initial", c.grip_mu_initial, "must lie in [grip_mu_min, grip_mu_max]");
  }
  non_negative("grip_mu_rise_per_s", c.grip_mu_rise_per_s);
  positive("grip_mu_drop", c.grip_mu_drop);
  if (!(c.grip_mu_drop < 1.0)) fail("grip_mu_drop", c.grip_mu_drop, "must be < 1");
  positive("grip_slip_step", c.grip_slip_step);
  at_most("grip_slip_step", c.grip_slip_step, "2", 2.0);
  non_negative("grip_safe_s", c.grip_safe_s);
  positive("grip_relax_s", c.grip_relax_s);
  positive("grip_load_window_s", c.grip_load_window_s);
  positive("grip_servo_gain_mps_per_n", c.grip_servo_gain_mps_per_n);
  positive("grip_servo_gain_period_s", c.grip_servo_gain_period_s);
  positive("grip_servo_max_speed_mps", c.grip_servo_max_speed_mps);
  at_most("grip_servo_max_speed_mps", c.grip_servo_max_speed_mps, "max_finger_speed_mps",
          c.max_finger_speed_mps);
  positive("grip_force_rate_nps", c.grip_force_rate_nps);
  non_negative("grip_reach_timeout_s", c.grip_reach_timeout_s);
  non_negative("grip_ff_accel_mps2", c.grip_ff_accel_mps2);
  non_negative("grip_ff_lead_s", c.grip_ff_lead_s);
}

}  // namespace

void Config::validate() const {
  switch (task) {
    case Task::kGraspMoveTwist:
    case Task::kGraspMoveRelease:
    case Task::kTwistOnly:
      break;
    default:
      fail("task", static_cast<int>(task), "unknown task");
  }

  positive("f1_n", f1_n);
  positive("f2_n", f2_n);
  if (!(f2_n > f1_n)) fail("f2_n", f2_n, "must be > f1_n");
  positive("dr_mm", dr_mm);
  positive("twist_dr_factor", twist_dr_factor);
  finite("gravity_axis.x", gravity_axis.x);
  finite("gravity_axis.y", gravity_axis.y);
  finite("gravity_axis.z", gravity_axis.z);
  if (std::abs(norm(gravity_axis) - 1.0) > 1e-6) {
    fail("gravity_axis", norm(gravity_axis), "must have unit length");
  }
  // The displacement lies in the x_f-y_f plane: an axis along z_f would classify nothing.
  if (std::hypot(gravity_axis.x, gravity_axis.y) < 1e-3) {
    fail("gravity_axis.z", gravity_axis.z, "the axis must not lie along z_f");
  }
  non_negative("direction_deadband_mm", direction_deadband_mm);
  switch (slip_detector) {
    case SlipDetectorKind::kPaper:
    case SlipDetectorKind::kField:
    case SlipDetectorKind::kLearned:
      break;
    default:
      fail("slip_detector", static_cast<int>(slip_detector), "unknown detector");
  }
  non_negative("field_partial_slip_ratio", field_partial_slip_ratio);
  at_most("field_partial_slip_ratio", field_partial_slip_ratio, "1", 1.0);
  positive("field_edge_ratio", field_edge_ratio);
  at_most("field_edge_ratio", field_edge_ratio, "1", 1.0);
  positive("field_drop_ratio", field_drop_ratio);
  positive("field_mu_initial", field_mu_initial);
  non_negative("field_min_fz_n", field_min_fz_n);
  non_negative("field_arm_speed_mps", field_arm_speed_mps);
  non_negative("field_arm_yaw_rate_rps", field_arm_yaw_rate_rps);
  positive("load_transfer_n", load_transfer_n);
  positive("lift_confirm_s", lift_confirm_s);

  switch (grip) {
    case GripKind::kPaper:
    case GripKind::kMargin:
      break;
    default:
      fail("grip", static_cast<int>(grip), "unknown grip");
  }
  validate_margin_grip(*this);

  positive("max_finger_speed_mps", max_finger_speed_mps);
  positive("approach_speed_mps", approach_speed_mps);
  at_most("approach_speed_mps", approach_speed_mps, "max_finger_speed_mps", max_finger_speed_mps);
  positive("recompress_gain_mps", recompress_gain_mps);
  at_most("recompress_gain_mps", recompress_gain_mps, "max_finger_speed_mps", max_finger_speed_mps);
  positive("recompress_duration_s", recompress_duration_s);
  positive("recompress_max_f2_fraction", recompress_max_f2_fraction);
  at_most("recompress_max_f2_fraction", recompress_max_f2_fraction, "1", 1.0);
  positive("backoff_speed_mps", backoff_speed_mps);
  at_most("backoff_speed_mps", backoff_speed_mps, "max_finger_speed_mps", max_finger_speed_mps);

  finite("cap_x_m", cap_x_m);
  finite("cap_y_m", cap_y_m);
  finite("bottle_x_m", bottle_x_m);
  finite("bottle_y_m", bottle_y_m);
  finite("grasp_yaw_rad", grasp_yaw_rad);
  finite("grasp_height_m", grasp_height_m);
  finite("safe_height_m", safe_height_m);
  if (!(safe_height_m > grasp_height_m))
    fail("safe_height_m", safe_height_m, "must be > grasp_height_m");
  finite("carry_height_m", carry_height_m);
  if (!(carry_height_m > grasp_height_m)) {
    fail("carry_height_m", carry_height_m, "must be > grasp_height_m");
  }
  finite("lower_limit_m", lower_limit_m);
  if (!(lower_limit_m < carry_height_m)) {
    fail("lower_limit_m", lower_limit_m, "must be < carry_height_m");
  }
  positive("retract_height_m", retract_height_m);

  positive("move_speed_mps", move_speed_mps);
  positive("lift_speed_mps", lift_speed_mps);
  positive("carry_speed_mps", carry_speed_mps);
  positive("lower_speed_mps", lower_speed_mps);
  positive("max_yaw_rate_rps", max_yaw_rate_rps);
  positive("twist_yaw_rate_rps", twist_yaw_rate_rps);

  non_negative("grasp_settle_s", grasp_settle_s);
  positive("open_speed_mps", open_speed_mps);
  positive("open_distance_m", open_distance_m);
  non_negative("open_settle_s", open_settle_s);
  non_negative("resume_settle_s", resume_settle_s);

  positive("twist_angle_rad", twist_angle_rad);
  if (twist_angle_rad > 2.0 * std::numbers::pi) {
    fail("twist_angle_rad", twist_angle_rad, "must be at most one turn (2 pi)");
  }
  if (ns < 1) fail("ns", ns, "must be >= 1");
  if (cycle_slip_min < 1) fail("cycle_slip_min", cycle_slip_min, "must be >= 1");
  if (max_twist_cycles < 1) fail("max_twist_cycles", max_twist_cycles, "must be >= 1");
  positive("tight_torque_rise_nm", tight_torque_rise_nm);
  non_negative("tight_torque_rise_ratio", tight_torque_rise_ratio);
  positive("tight_level_s", tight_level_s);
  positive("tight_plateau_s", tight_plateau_s);
  non_negative("tight_plateau_fraction", tight_plateau_fraction);
  if (!(tight_plateau_fraction < 1.0)) {
    fail("tight_plateau_fraction", tight_plateau_fraction, "must be < 1");
  }

  positive("search_timeout_s", search_timeout_s);
  positive("segment_timeout_s", segment_timeout_s);
  positive("stale_after_s", stale_after_s);
  non_negative("stale_abort_s", stale_abort_s);
}

}  // namespace tactile::control
