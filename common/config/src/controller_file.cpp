#include "tactile/config/controller_file.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tactile::config {
namespace {

using control::Config;

struct DoubleField {
  const char* name;
  double Config::*member;
};

struct CountField {
  const char* name;
  std::uint32_t Config::*member;
};

const DoubleField kDoubles[] = {
    {"f1_n", &Config::f1_n},
    {"f2_n", &Config::f2_n},
    {"dr_mm", &Config::dr_mm},
    {"twist_dr_factor", &Config::twist_dr_factor},
    {"direction_deadband_mm", &Config::direction_deadband_mm},
    {"field_partial_slip_ratio", &Config::field_partial_slip_ratio},
    {"field_edge_ratio", &Config::field_edge_ratio},
    {"field_drop_ratio", &Config::field_drop_ratio},
    {"field_mu_initial", &Config::field_mu_initial},
    {"field_min_fz_n", &Config::field_min_fz_n},
    {"field_arm_speed_mps", &Config::field_arm_speed_mps},
    {"field_arm_yaw_rate_rps", &Config::field_arm_yaw_rate_rps},
    {"load_transfer_n", &Config::load_transfer_n},
    {"lift_confirm_s", &Config::lift_confirm_s},
    {"approach_speed_mps", &Config::approach_speed_mps},
    {"recompress_gain_mps", &Config::recompress_gain_mps},
    {"recompress_duration_s", &Config::recompress_duration_s},
    {"recompress_max_f2_fraction", &Config::recompress_max_f2_fraction},
    {"backoff_speed_mps", &Config::backoff_speed_mps},
    {"max_finger_speed_mps", &Config::max_finger_speed_mps},
    {"grip_touch_n", &Config::grip_touch_n},
    {"grip_min_n", &Config::grip_min_n},
    {"grip_lift_n", &Config::grip_lift_n},
    {"grip_loading_speed_mps", &Config::grip_loading_speed_mps},
    {"grip_loading_distance_m", &Config::grip_loading_distance_m},
    {"grip_margin", &Config::grip_margin},
    {"grip_twist_margin", &Config::grip_twist_margin},
    {"grip_mu_initial", &Config::grip_mu_initial},
    {"grip_mu_min", &Config::grip_mu_min},
    {"grip_mu_max", &Config::grip_mu_max},
    {"grip_mu_rise_per_s", &Config::grip_mu_rise_per_s},
    {"grip_mu_drop", &Config::grip_mu_drop},
    {"grip_slip_step", &Config::grip_slip_step},
    {"grip_safe_s", &Config::grip_safe_s},
    {"grip_relax_s", &Config::grip_relax_s},
    {"grip_load_window_s", &Config::grip_load_window_s},
    {"grip_servo_gain_mps_per_n", &Config::grip_servo_gain_mps_per_n},
    {"grip_servo_gain_period_s", &Config::grip_servo_gain_period_s},
    {"grip_reach_timeout_s", &Config::grip_reach_timeout_s},
    {"grip_servo_max_speed_mps", &Config::grip_servo_max_speed_mps},
    {"grip_force_rate_nps", &Config::grip_force_rate_nps},
    {"grip_ff_accel_mps2", &Config::grip_ff_accel_mps2},
    {"grip_ff_lead_s", &Config::grip_ff_lead_s},
    {"cap_x_m", &Config::cap_x_m},
    {"cap_y_m", &Config::cap_y_m},
    {"bottle_x_m", &Config::bottle_x_m},
    {"bottle_y_m", &Config::bottle_y_m},
    {"grasp_yaw_rad", &Config::grasp_yaw_rad},
    {"safe_height_m", &Config::safe_height_m},
    {"grasp_height_m", &Config::grasp_height_m},
    {"carry_height_m", &Config::carry_height_m},
    {"lower_limit_m", &Config::lower_limit_m},
    {"retract_height_m", &Config::retract_height_m},
    {"move_speed_mps", &Config::move_speed_mps},
    {"lift_speed_mps", &Config::lift_speed_mps},
    {"carry_speed_mps", &Config::carry_speed_mps},
    {"lower_speed_mps", &Config::lower_speed_mps},
    {"max_yaw_rate_rps", &Config::max_yaw_rate_rps},
    {"twist_yaw_rate_rps", &Config::twist_yaw_rate_rps},
    {"grasp_settle_s", &Config::grasp_settle_s},
    {"open_speed_mps", &Config::open_speed_mps},
    {"open_distance_m", &Config::open_distance_m},
    {"open_settle_s", &Config::open_settle_s},
    {"resume_settle_s", &Config::resume_settle_s},
    {"twist_angle_rad", &Config::twist_angle_rad},
    {"tight_torque_rise_nm", &Config::tight_torque_rise_nm},
    {"tight_torque_rise_ratio", &Config::tight_torque_rise_ratio},
    {"tight_level_s", &Config::tight_level_s},
    {"tight_plateau_s", &Config::tight_plateau_s},
    {"tight_plateau_fraction", &Config::tight_plateau_fraction},
    {"search_timeout_s", &Config::search_timeout_s},
    {"segment_timeout_s", &Config::segment_timeout_s},
    {"stale_after_s", &Config::stale_after_s},
    {"stale_abort_s", &Config::stale_abort_s},
};

const CountField kCounts[] = {
    {"ns", &Config::ns},
    {"cycle_slip_min", &Config::cycle_slip_min},
    {"max_twist_cycles", &Config::max_twist_cycles},
};

}  // namespace

std::vector<std::string> controller_config_keys() {
  std::vector<std::string> keys{"task", "slip_detector", "grip"};
  for (const auto& f : kDoubles)
    keys.emplace_back(f.name);
  keys.emplace_back("twist_angle_deg");
  keys.emplace_back("gravity_axis");
  keys.emplace_back("tighten_clockwise");
  for (const auto& f : kCounts)
    keys.emplace_back(f.name);
  return keys;
}

bool set_controller_field(control::Config& cfg, std::string_view key, double value) {
  for (const auto& f : kDoubles) {
    if (key == f.name) {
      cfg.*(f.member) = value;
      return true;
    }
  }
  for (const auto& f : kCounts) {
    if (key == f.name) {
      cfg.*(f.member) = static_cast<std::uint32_t>(std::clamp(std::round(value), 0.0, 1e6));
      return true;
    }
  }
  if (key == "twist_angle_deg") {
    cfg.twist_angle_rad = value * std::numbers::pi / 180.0;
    return true;
  }
  return false;
}

control::Config parse_controller_config(const Node& section) {
  Config cfg;
  if (section.is_null()) return cfg;
  if (!section.is_map())
    section.fail("must be a mapping of controller parameters, is " + section.text());
  section.refuse_unknown_keys(controller_config_keys());

  if (auto t = section.find("task")) {
    const std::string v = t->as_string();
    bool known = false;
    for (auto task : {control::Task::kGraspMoveTwist, control::Task::kGraspMoveRelease,
                      control::Task::kTwistOnly}) {
      if (v == control::to_string(task)) {
        cfg.task = task;
        known = true;
      }
    }
    if (!known)
      t->fail("must be grasp_move_twist, grasp_move_release or twist_only, is " + t->text());
  }
  if (auto n = section.find("slip_detector")) {
    const auto kind = control::slip_detector_from_string(n->as_string());
    if (!kind) n->fail(std::string("must be ") + control::kSlipDetectorNames + ", is " + n->text());
    cfg.slip_detector = *kind;
  }
  if (auto n = section.find("grip")) {
    const auto kind = control::grip_from_string(n->as_string());
    if (!kind) n->fail(std::string("must be ") + control::kGripNames + ", is " + n->text());
    cfg.grip = *kind;
  }
  for (const auto& f : kDoubles) {
    if (auto n = section.find(f.name)) cfg.*(f.member) = n->as_double();
  }
  if (auto n = section.find("twist_angle_deg")) {
    if (section.has("twist_angle_rad"))
      n->fail("give twist_angle_deg or twist_angle_rad, not both");
    cfg.twist_angle_rad = n->as_double() * std::numbers::pi / 180.0;
  }
  for (const auto& f : kCounts) {
    if (auto n = section.find(f.name)) {
      const std::int64_t v = n->as_int();
      if (v < 0 || v > 1000000) n->fail("must be a count from 0 to 1000000, is " + n->text());
      cfg.*(f.member) = static_cast<std::uint32_t>(v);
    }
  }
  if (auto n = section.find("gravity_axis")) {
    const auto v = n->as_doubles();
    if (v.size() != 3)
      n->fail("must be a list of 3 numbers [x, y, z], has " + std::to_string(v.size()));
    cfg.gravity_axis = {v[0], v[1], v[2]};
  }
  if (auto n = section.find("tighten_clockwise")) cfg.tighten_clockwise = n->as_bool();

  try {
    cfg.validate();
  } catch (const std::invalid_argument& e) {
    section.fail(e.what());
  }
  return cfg;
}

}  // namespace tactile::config
