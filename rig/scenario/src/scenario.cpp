#include "tactile/rig/scenario.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string_view>

#include "tactile/config/calibration_file.hpp"
#include "tactile/config/controller_file.hpp"
#include "tactile/config/yaml.hpp"
#include "tactile/control/config.hpp"
#include "tactile/control/types.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/text.hpp"

namespace tactile::rig {
namespace {

using config::Node;

std::string number_text(double v) {
  std::string s = std::to_string(v);
  while (s.size() > 1 && s.back() == '0')
    s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

double checked(const Node& n, double lo, double hi) {
  const double v = n.as_double();
  if (v < lo || v > hi) {
    n.fail("must be within [" + number_text(lo) + ", " + number_text(hi) + "], is " + n.text());
  }
  return v;
}

// A required number within [lo, hi].
double need(const Node& sec, std::string_view key, double lo, double hi) {
  return checked(sec[key], lo, hi);
}

// An optional number within [lo, hi].
double want(const Node& sec, std::string_view key, double fallback, double lo, double hi) {
  auto n = sec.find(key);
  return n ? checked(*n, lo, hi) : fallback;
}

// A pair [dx, dy] in `units` (`unit` for short), each within [-limit, limit] (bottle.displaced_mm,
// sensor.layout_offset_px).
std::array<double, 2> offset_pair(const Node& n, double limit, const char* units,
                                  const char* unit) {
  const std::vector<double> v = n.as_doubles();
  if (v.size() != 2) n.fail(std::string("must be [dx, dy] in ") + units);
  for (const double d : v) {
    if (!(std::abs(d) <= limit)) {
      n.fail("must be within [-" + number_text(limit) + ", " + number_text(limit) + "] " + unit +
             " each, is " + number_text(d));
    }
  }
  return {v[0], v[1]};
}

// A named choice (slip_detector, grip, element_model), refused unless `parse` knows it.
template <typename Parse>
std::string choice(const Node& n, Parse parse, const char* names) {
  if (!parse(n.as_string())) n.fail(std::string("must be ") + names + ", is " + n.text());
  return n.as_string();
}

}  // namespace

int Scenario::steps_per_frame() const {
  return std::max(1, static_cast<int>(std::lround(1.0 / (camera.fps * dt_s))));
}

double Scenario::step_s() const {
  return 1.0 / (camera.fps * steps_per_frame());
}

const std::vector<std::string>& controller_keys() {
  // The controller's own keys (config::controller_config_keys), less those the scenario's world
  // decides: where the cap and the bottle are, which way the thread turns, gravity and the task.
  static const std::vector<std::string> keys = [] {
    const std::array<std::string_view, 7> world{
        "task",       "gravity_axis", "cap_x_m",          "cap_y_m",
        "bottle_x_m", "bottle_y_m",   "tighten_clockwise"};
    std::vector<std::string> k = config::controller_config_keys();
    std::erase_if(k, [&](const std::string& key) {
      return std::find(world.begin(), world.end(), key) != world.end();
    });
    return k;
  }();
  return keys;
}

namespace {

// Required: fps, width, height, bit_depth, noise_sigma.
void parse_camera(const Node& cam, CameraParams& c) {
  cam.refuse_unknown_keys({"fps", "width", "height", "bit_depth", "noise_sigma", "shot_noise_gain",
                           "background", "vignetting", "refresh_outside_disks"});
  c.fps = need(cam, "fps", 1.0, 1000.0);
  c.width = static_cast<int>(need(cam, "width", 160, 4096));
  c.height = static_cast<int>(need(cam, "height", 120, 4096));
  if (cam["width"].as_int() != c.width) cam["width"].fail("must be a whole number");
  if (cam["height"].as_int() != c.height) cam["height"].fail("must be a whole number");
  const Node depth = cam["bit_depth"];
  c.bit_depth = static_cast<int>(depth.as_int());
  if (c.bit_depth != 8 && c.bit_depth != 16) depth.fail("must be 8 or 16, is " + depth.text());
  c.noise_sigma = need(cam, "noise_sigma", 0.0, 30.0);
  c.shot_noise_gain = want(cam, "shot_noise_gain", c.shot_noise_gain, 0.0, 1e6);
  c.background = want(cam, "background", c.background, 0.0, 200.0);
  c.vignetting = want(cam, "vignetting", c.vignetting, 0.0, 0.9);
  c.refresh_outside_disks = cam.get("refresh_outside_disks", c.refresh_outside_disks);
}

// Required: mass_kg, radius_mm, friction.
void parse_cap(const Node& cap, CapParams& cp) {
  cap.refuse_unknown_keys({"mass_kg", "radius_mm", "friction", "height_mm", "kinetic_ratio",
                           "inertia_factor", "x_m", "y_m", "table_friction", "held_to_table",
                           "crush_force_n"});
  cp.mass_kg = need(cap, "mass_kg", 1e-4, 1.0);
  cp.radius_m = need(cap, "radius_mm", 5.0, 50.0) / 1000.0;
  cp.friction = need(cap, "friction", 0.05, 3.0);
  cp.height_m = want(cap, "height_mm", cp.height_m * 1000.0, 5.0, 60.0) / 1000.0;
  cp.kinetic_ratio = want(cap, "kinetic_ratio", cp.kinetic_ratio, 0.05, 1.0);
  cp.inertia_factor = want(cap, "inertia_factor", cp.inertia_factor, 0.1, 1.0);
  cp.x_m = want(cap, "x_m", cp.x_m, -2.0, 2.0);
  cp.y_m = want(cap, "y_m", cp.y_m, -2.0, 2.0);
  cp.table_friction = want(cap, "table_friction", cp.table_friction, 0.0, 3.0);
  cp.held_to_table = cap.get("held_to_table", cp.held_to_table);
  cp.crush_force_n = want(cap, "crush_force_n", cp.crush_force_n, 1e-3, 1000.0);
}

// Required: free_turn_deg.
void parse_bottle(const Node& bottle, BottleParams& bp) {
  bottle.refuse_unknown_keys({"free_turn_deg", "x_m", "y_m", "height_mm", "free_torque_nm",
                              "tight_stiffness_nm_per_rad", "capture_radius_mm",
                              "tighten_clockwise", "displaced_mm"});
  bp.free_turn_deg = need(bottle, "free_turn_deg", 0.0, 3600.0);
  bp.x_m = want(bottle, "x_m", bp.x_m, -2.0, 2.0);
  bp.y_m = want(bottle, "y_m", bp.y_m, -2.0, 2.0);
  bp.height_m = want(bottle, "height_mm", bp.height_m * 1000.0, 20.0, 500.0) / 1000.0;
  bp.free_torque_nm = want(bottle, "free_torque_nm", bp.free_torque_nm, 0.0, 1.0);
  bp.tight_stiffness_nm_per_rad =
      want(bottle, "tight_stiffness_nm_per_rad", bp.tight_stiffness_nm_per_rad, 0.01, 100.0);
  bp.capture_radius_m =
      want(bottle, "capture_radius_mm", bp.capture_radius_m * 1000.0, 0.1, 20.0) / 1000.0;
  bp.tighten_clockwise = bottle.get("tighten_clockwise", bp.tighten_clockwise);
  if (auto displaced = bottle.find("displaced_mm")) {
    const std::array<double, 2> v = offset_pair(*displaced, 1000.0, "millimetres", "mm");
    bp.displaced_x_m = v[0] / 1000.0;
    bp.displaced_y_m = v[1] / 1000.0;
  }
}

// Required: vibration_mm, vibration_hz.
void parse_arm(const Node& arm, ArmParams& ap) {
  arm.refuse_unknown_keys({"vibration_mm", "vibration_hz", "vibration_rise_s",
                           "vibration_full_speed_mps", "max_accel_mps2", "stop_decel_mps2",
                           "max_yaw_accel_rps2", "stop_yaw_decel_rps2", "finger_accel_mps2",
                           "finger_open_mm", "start_m", "start_yaw_deg"});
  ap.vibration_m = need(arm, "vibration_mm", 0.0, 5.0) / 1000.0;
  ap.vibration_hz = need(arm, "vibration_hz", 0.0, 200.0);
  ap.vibration_rise_s = want(arm, "vibration_rise_s", ap.vibration_rise_s, 0.0, 10.0);
  ap.max_accel_mps2 = want(arm, "max_accel_mps2", ap.max_accel_mps2, 0.01, 50.0);
  ap.vibration_full_speed_mps =
      want(arm, "vibration_full_speed_mps", ap.vibration_full_speed_mps, 0.001, 10.0);
  ap.stop_decel_mps2 = want(arm, "stop_decel_mps2", ap.stop_decel_mps2, 0.01, 100.0);
  ap.max_yaw_accel_rps2 = want(arm, "max_yaw_accel_rps2", ap.max_yaw_accel_rps2, 0.01, 500.0);
  ap.stop_yaw_decel_rps2 = want(arm, "stop_yaw_decel_rps2", ap.stop_yaw_decel_rps2, 0.01, 500.0);
  ap.finger_accel_mps2 = want(arm, "finger_accel_mps2", ap.finger_accel_mps2, 0.01, 100.0);
  ap.finger_open_m = want(arm, "finger_open_mm", ap.finger_open_m * 1000.0, 1.0, 40.0) / 1000.0;
  if (auto start = arm.find("start_m")) {
    const std::vector<double> v = start->as_doubles();
    if (v.size() != 3) start->fail("must be [x, y, z] in metres");
    ap.start_position_m = {v[0], v[1], v[2]};
  }
  ap.start_yaw_rad = want(arm, "start_yaw_deg", 0.0, -360.0, 360.0) * std::numbers::pi / 180.0;
}

void parse_fingertip(const Node& ft, FingertipParams& fp) {
  ft.refuse_unknown_keys({"dome_radius_mm", "ring_polar_deg", "normal_stiffness_n_per_mm",
                          "normal_damping_nspm", "tangential_damping_nspm"});
  fp.dome_radius_m = want(ft, "dome_radius_mm", fp.dome_radius_m * 1000.0, 2.0, 50.0) / 1000.0;
  if (auto rings = ft.find("ring_polar_deg")) {
    const std::vector<double> v = rings->as_doubles();
    if (v.size() != 4 || v[0] != 0.0) rings->fail("must be 4 angles starting with 0");
    for (std::size_t i = 1; i < 4; ++i) {
      if (!(v[i] > v[i - 1]) || v[i] >= 80.0) rings->fail("must increase and stay below 80");
    }
    for (std::size_t i = 0; i < 4; ++i)
      fp.ring_polar_deg[i] = v[i];
  }
  fp.normal_stiffness_npm =
      want(ft, "normal_stiffness_n_per_mm", fp.normal_stiffness_npm / 1000.0, 0.05, 100.0) * 1000.0;
  fp.normal_damping_nspm = want(ft, "normal_damping_nspm", fp.normal_damping_nspm, 0.0, 10.0);
  fp.tangential_damping_nspm =
      want(ft, "tangential_damping_nspm", fp.tangential_damping_nspm, 0.0, 10.0);
}

void parse_optics(const Node& so, SensorOpticsParams& o) {
  so.refuse_unknown_keys({"element_model", "calibration", "mm_per_px", "disk_radius_px",
                          "spot_peak_ref", "spot_sigma_min_px", "spot_sigma_max_px", "contact_on",
                          "contact_off", "normal_curve_error", "shear_curve_error",
                          "layout_offset_px"});
  if (auto model = so.find("element_model")) {
    o.element_model =
        *element_model_from_string(choice(*model, element_model_from_string, kElementModelNames));
  }
  o.mm_per_px = want(so, "mm_per_px", o.mm_per_px, 0.001, 1.0);
  o.disk_radius_px = want(so, "disk_radius_px", o.disk_radius_px, 4.0, 20.0);
  o.spot_peak_ref = want(so, "spot_peak_ref", o.spot_peak_ref, 5.0, 250.0);
  o.spot_sigma_min_px = want(so, "spot_sigma_min_px", o.spot_sigma_min_px, 0.5, 10.0);
  o.spot_sigma_max_px = want(so, "spot_sigma_max_px", o.spot_sigma_max_px, 0.5, 10.0);
  if (o.spot_sigma_max_px < o.spot_sigma_min_px)
    so["spot_sigma_max_px"].fail("must be at least spot_sigma_min_px");
  o.contact_on = want(so, "contact_on", o.contact_on, 1.0, 1e5);
  o.contact_off = want(so, "contact_off", o.contact_off, 0.0, o.contact_on);
  o.normal_curve_error = want(so, "normal_curve_error", o.normal_curve_error, -0.5, 0.5);
  o.shear_curve_error = want(so, "shear_curve_error", o.shear_curve_error, -0.5, 0.5);
  if (auto offset = so.find("layout_offset_px")) {
    const std::array<double, 2> v = offset_pair(*offset, 5.0, "pixels", "px");
    o.layout_offset_px = {v[0], v[1]};
  }
}

std::string vector_text(Vec3 v) {
  return "[" + number_text(v.x) + ", " + number_text(v.y) + ", " + number_text(v.z) + "]";
}

// sensor.calibration (docs/rig.md, "A lab's sensor"): the file's layout, curves, thresholds and
// image instead of make_calibration's. The sensor keys that would set the same things are refused
// beside it, and the camera's image must be the file's: nothing is silently overridden.
void parse_lab_sensor(const Node& so, const Node& cam, Scenario& s) {
  const auto file = so.find("calibration");
  if (!file) return;
  for (const char* key : {"mm_per_px", "disk_radius_px", "contact_on", "contact_off"}) {
    if (auto k = so.find(key))
      k->fail("is the calibration file's with sensor.calibration: remove it; is " + k->text());
  }
  std::filesystem::path path = file->as_string();
  if (path.empty()) file->fail("must name a calibration file (tactile-calibration/1)");
  if (path.is_relative()) path = std::filesystem::path(s.source).parent_path() / path;
  try {
    s.calibration = load_lab_calibration(path, s.world);
  } catch (const config::ConfigError& e) {
    file->fail(e.what());
  }
  s.calibration_file = path;
  const Calibration& c = *s.calibration;
  const std::array<std::pair<const char*, int>, 3> image{
      {{"width", c.width}, {"height", c.height}, {"bit_depth", c.bit_depth}}};
  const std::array<int, 3> camera{s.camera.width, s.camera.height, s.camera.bit_depth};
  for (std::size_t i = 0; i < image.size(); ++i) {
    if (camera[i] == image[i].second) continue;
    const Node key = cam[image[i].first];
    key.fail(std::string("must be the calibration's image.") + image[i].first + ", " +
             std::to_string(image[i].second) + " (" + path.string() + "), is " + key.text());
  }
}

void parse_sim(const Node& sim, Scenario& s) {
  sim.refuse_unknown_keys({"dt_s", "max_time_s", "settle_after_done_s", "partial_slip_ratio"});
  s.dt_s = want(sim, "dt_s", s.dt_s, 1e-6, 1e-3);
  s.max_time_s = want(sim, "max_time_s", s.max_time_s, 0.1, 3600.0);
  s.settle_after_done_s = want(sim, "settle_after_done_s", s.settle_after_done_s, 0.0, 10.0);
  s.partial_slip_ratio = want(sim, "partial_slip_ratio", s.partial_slip_ratio, 0.05, 1.0);
}

// A direction in the world frame: three numbers, not all zero; made a unit vector.
Vec3 parse_direction(const Node& n) {
  const std::vector<double> v = n.as_doubles();
  if (v.size() != 3) n.fail("must be [x, y, z] in the world frame, is " + n.text());
  const Vec3 d{v[0], v[1], v[2]};
  const double length = norm(d);
  if (!(length > 0)) n.fail("must not be [0, 0, 0]");
  return (1.0 / length) * d;
}

// The controller's stage names (control::to_string(Phase)) a disturbance can be timed from.
std::vector<std::string> stage_names() {
  std::vector<std::string> names;
  for (int p = 0; p <= static_cast<int>(control::Phase::kAborted); ++p)
    names.emplace_back(control::to_string(static_cast<control::Phase>(p)));
  return names;
}

// start_s, into `stage` when one is named, else on the run's clock: into `start` (absolute) or
// `by_stage`.
void parse_start(const Node& sec, double& start, DisturbanceStart& by_stage) {
  const double at = need(sec, "start_s", 0.0, 3600.0);
  const auto stage = sec.find("stage");
  if (!stage) {
    start = at;
    return;
  }
  const std::vector<std::string> names = stage_names();
  const std::string name = stage->as_string();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string known;
    for (const std::string& n : names)
      known += (known.empty() ? "" : ", ") + n;
    const std::string close = util::closest_match(name, names);
    stage->fail("must be one of the controller's stages (" + known + "), is " + stage->text() +
                (close.empty() ? "" : " (did you mean '" + close + "'?)"));
  }
  by_stage = {name, at};
}

// Each disturbance is optional; absent, the world has none.
void parse_disturbance(const Node& dist, Scenario& s) {
  if (!dist.is_map()) dist.fail("must be a mapping of pull, mass_step, knock");
  dist.refuse_unknown_keys({"pull", "mass_step", "knock"});
  DisturbanceParams& d = s.world.disturbance;
  auto& by_stage = s.disturbance_start;
  if (auto pull = dist.find("pull")) {
    pull->refuse_unknown_keys({"force_n", "direction", "stage", "start_s", "ramp_s", "duration_s"});
    d.pull.force_n = need(*pull, "force_n", 1e-4, 100.0);
    if (auto dir = pull->find("direction")) d.pull.direction = parse_direction(*dir);
    parse_start(*pull, d.pull.start_s, by_stage[static_cast<std::size_t>(DisturbanceKind::kPull)]);
    d.pull.ramp_s = want(*pull, "ramp_s", 0.0, 0.0, 60.0);
    if (auto duration = pull->find("duration_s"))
      d.pull.duration_s = checked(*duration, 1e-3, 3600.0);
  }
  if (auto step = dist.find("mass_step")) {
    step->refuse_unknown_keys({"added_kg", "stage", "start_s"});
    d.mass_step.added_kg = need(*step, "added_kg", 1e-5, 1.0);
    parse_start(*step, d.mass_step.start_s,
                by_stage[static_cast<std::size_t>(DisturbanceKind::kMassStep)]);
  }
  if (auto knock = dist.find("knock")) {
    knock->refuse_unknown_keys({"impulse_ns", "direction", "stage", "start_s", "duration_s"});
    d.knock.impulse_ns = need(*knock, "impulse_ns", 1e-6, 10.0);
    if (auto dir = knock->find("direction")) d.knock.direction = parse_direction(*dir);
    parse_start(*knock, d.knock.start_s,
                by_stage[static_cast<std::size_t>(DisturbanceKind::kKnock)]);
    d.knock.duration_s = want(*knock, "duration_s", d.knock.duration_s, 1e-4, 0.1);
  }
}

// Overrides of the controller's settings, by the names of controller_keys().
void parse_controller(const Node& ctl, Scenario& s) {
  if (!ctl.is_map()) ctl.fail("must be a mapping of controller settings");
  ctl.refuse_unknown_keys(controller_keys());
  for (const std::string& key : ctl.keys()) {
    if (key == "slip_detector") {
      s.slip_detector =
          choice(ctl[key], control::slip_detector_from_string, control::kSlipDetectorNames);
    } else if (key == "grip") {
      s.grip = choice(ctl[key], control::grip_from_string, control::kGripNames);
    } else {
      s.controller.emplace_back(key, checked(ctl[key], -1e6, 1e6));
    }
  }
}

}  // namespace

Scenario parse_scenario(const std::string& text, const std::string& source) {
  const Node root = config::parse_yaml(text, source);
  if (!root.is_map()) root.fail("a scenario must be a mapping");
  root.refuse_unknown_keys({"format", "seed", "camera", "cap", "bottle", "arm", "fingertip",
                            "sensor", "sim", "controller", "disturbance"});
  Scenario s;
  s.source = source;
  const Node format = root["format"];
  if (format.as_string() != kScenarioFormat) {
    format.fail(std::string("must be '") + kScenarioFormat + "', is " + format.text());
  }
  const Node seed = root["seed"];
  const std::int64_t seed_value = seed.as_int();
  if (seed_value < 0) seed.fail("must be a non-negative whole number, is " + seed.text());
  s.seed = static_cast<std::uint64_t>(seed_value);

  parse_camera(root["camera"], s.camera);
  parse_cap(root["cap"], s.world.cap);
  parse_bottle(root["bottle"], s.world.bottle);
  parse_arm(root["arm"], s.world.arm);
  if (auto ft = root.find("fingertip")) parse_fingertip(*ft, s.world.fingertip);
  if (auto so = root.find("sensor")) parse_optics(*so, s.optics);
  if (auto sim = root.find("sim")) parse_sim(*sim, s);
  if (1.0 / (s.camera.fps * s.dt_s) < 1.0) {
    root["sim"]["dt_s"].fail("must not exceed the camera's frame period");
  }
  if (auto ctl = root.find("controller")) parse_controller(*ctl, s);
  if (auto dist = root.find("disturbance")) parse_disturbance(*dist, s);
  // Last: the world's fingertip (its normals) is complete.
  if (auto so = root.find("sensor")) parse_lab_sensor(*so, root["camera"], s);

  // The fingertip's tangential law is the sensor's calibrated shear curve (see docs/rig.md).
  s.world.fingertip.shear_curve = s.calibration
                                      ? s.calibration->shear_curve
                                      : PiecewiseLinear({0.0, 0.02, 0.08}, {0.0, 0.05, 0.4});
  return s;
}

void check_lab_calibration(const Calibration& cal, const std::string& source,
                           std::span<const Vec3> world_normals) {
  if (cal.elements.size() != world_normals.size()) {
    throw config::ConfigError(
        source + ": key 'elements': must hold the rig fingertip's " +
        std::to_string(world_normals.size()) +
        " elements (element k of the file is the fingertip's element k), holds " +
        std::to_string(cal.elements.size()));
  }
  for (std::size_t k = 0; k < world_normals.size(); ++k) {
    const Vec3 n = cal.elements[k].normal;
    const Vec3 w = world_normals[k];
    const double cosine = std::clamp(dot(n, w) / (norm(n) * norm(w)), -1.0, 1.0);
    const double angle_deg = std::acos(cosine) * 180.0 / std::numbers::pi;
    if (angle_deg <= kLabNormalToleranceDeg) continue;
    throw config::ConfigError(
        source + ": key 'elements[" + std::to_string(k) + "].normal': (element id " +
        std::to_string(cal.elements[k].id) + ") is " + vector_text(n) + ", " +
        number_text(std::round(angle_deg * 100.0) / 100.0) +
        " deg from the rig fingertip's element " + std::to_string(k) + " " + vector_text(w) +
        "; at most " + number_text(kLabNormalToleranceDeg) +
        " deg (the elements in the fingertip's order: rings of 1, 8, 16, 16 at "
        "fingertip.ring_polar_deg)");
  }
}

Calibration load_lab_calibration(const std::filesystem::path& file, const WorldParams& world) {
  std::vector<std::string> warnings;
  Calibration cal = config::load_calibration(file, &warnings);
  for (const std::string& w : warnings)
    util::log_warn("{}", w);
  check_lab_calibration(cal, file.string(), World(world).element_normals());
  return cal;
}

LabSensor load_lab_sensor(const std::filesystem::path& file, const WorldParams& world) {
  const std::filesystem::path absolute = std::filesystem::absolute(file);
  const Calibration cal = load_lab_calibration(absolute, world);
  return {absolute.string(), cal.width, cal.height, cal.bit_depth};
}

Scenario load_scenario(const std::filesystem::path& path) {
  std::string text;
  try {
    text = util::read_file(path);
  } catch (const std::exception& e) {
    throw config::ConfigError(e.what());
  }
  return parse_scenario(text, path.string());
}

}  // namespace tactile::rig
