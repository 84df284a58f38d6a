// Scenario files (docs/rig.md, "Scenario files"): the bundled ones load, and every bad
// file is refused with a message naming file, line, key and value.
#include "tactile/rig/scenario.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "tactile/config/calibration_file.hpp"
#include "tactile/config/controller_file.hpp"
#include "tactile/config/yaml.hpp"
#include "tactile/control/config.hpp"
#include "tactile/extractor.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/util/files.hpp"

namespace tactile::rig {
namespace {

const std::string kMinimal = R"(format: tactile-scenario/1
seed: 1
camera: {fps: 100, width: 640, height: 480, bit_depth: 8, noise_sigma: 2.0}
cap: {mass_kg: 0.010, radius_mm: 15.0, friction: 0.8}
bottle: {free_turn_deg: 240.0}
arm: {vibration_mm: 0.2, vibration_hz: 12.0}
)";

std::string error_of(const std::string& text) {
  try {
    parse_scenario(text, "s.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Scenario, TheInterfaceKeysAreEnoughAndDefaultsFillTheRest) {
  const Scenario s = parse_scenario(kMinimal, "s.yaml");
  EXPECT_EQ(s.seed, 1U);
  EXPECT_EQ(s.camera.fps, 100.0);
  EXPECT_EQ(s.camera.bit_depth, 8);
  EXPECT_DOUBLE_EQ(s.world.cap.radius_m, 0.015);
  EXPECT_DOUBLE_EQ(s.world.arm.vibration_m, 0.0002);
  EXPECT_DOUBLE_EQ(s.world.bottle.free_turn_deg, 240.0);
  EXPECT_EQ(s.steps_per_frame(), 100);
  EXPECT_TRUE(s.controller.empty());
}

TEST(Scenario, BundledScenariosLoad) {
  const std::filesystem::path dir = TACTILE_RIG_SCENARIOS;
  const Scenario d = load_scenario(dir / "default.yaml");
  EXPECT_EQ(d.world.cap.mass_kg, 0.020);
  int variations = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "variations")) {
    EXPECT_NO_THROW(load_scenario(entry.path())) << entry.path();
    ++variations;
  }
  EXPECT_EQ(variations, 10);
}

TEST(Scenario, ErrorsNameFileLineKeyAndValue) {
  std::string e = error_of(kMinimal + "sim: {dt_s: 0.5}\n");
  EXPECT_NE(e.find("s.yaml:7"), std::string::npos) << e;
  EXPECT_NE(e.find("sim.dt_s"), std::string::npos) << e;
  EXPECT_NE(e.find("0.5"), std::string::npos) << e;

  std::string no_cap = kMinimal;
  no_cap.replace(no_cap.find("cap:"), no_cap.find("bottle:") - no_cap.find("cap:"), "");
  e = error_of(no_cap);
  EXPECT_NE(e.find("'cap' is missing"), std::string::npos) << e;

  std::string bad_depth = kMinimal;
  bad_depth.replace(bad_depth.find("bit_depth: 8"), 12, "bit_depth: 12");
  e = error_of(bad_depth);
  EXPECT_NE(e.find("camera.bit_depth"), std::string::npos) << e;
  EXPECT_NE(e.find("12"), std::string::npos) << e;

  e = error_of(kMinimal + "cap_typo: 1\n");
  EXPECT_NE(e.find("unknown key 'cap_typo'"), std::string::npos) << e;

  e = error_of(kMinimal + "controller: {f9_n: 1}\n");
  EXPECT_NE(e.find("unknown key 'f9_n' in 'controller' (did you mean 'f1_n'?)"), std::string::npos)
      << e;

  std::string misspelt = kMinimal;
  misspelt.replace(misspelt.find("friction"), 8, "fricton");
  e = error_of(misspelt);
  EXPECT_NE(e.find("unknown key 'fricton' in 'cap' (did you mean 'friction'?)"), std::string::npos)
      << e;

  std::string bad_format = kMinimal;
  bad_format.replace(0, bad_format.find('\n'), "format: tactile-scenario/2");
  e = error_of(bad_format);
  EXPECT_NE(e.find("s.yaml:1"), std::string::npos) << e;
  EXPECT_NE(e.find("tactile-scenario/2"), std::string::npos) << e;
}

// The sweep's negative cases (docs/slip.md): the bottle displaced from the controller's place, the
// cap held to the table. Strict like every key.
TEST(Scenario, NegativeCaseKeys) {
  std::string text = kMinimal;
  text.replace(text.find("friction: 0.8"), 13, "friction: 0.8, held_to_table: true");
  text.replace(text.find("free_turn_deg: 240.0"), 20,
               "free_turn_deg: 240.0, displaced_mm: [60, -80]");
  const Scenario s = parse_scenario(text, "s.yaml");
  EXPECT_TRUE(s.world.cap.held_to_table);
  EXPECT_DOUBLE_EQ(s.world.bottle.displaced_x_m, 0.060);
  EXPECT_DOUBLE_EQ(s.world.bottle.displaced_y_m, -0.080);
  const Scenario plain = parse_scenario(kMinimal, "s.yaml");
  EXPECT_FALSE(plain.world.cap.held_to_table);
  EXPECT_EQ(plain.world.bottle.displaced_x_m, 0.0);
  EXPECT_EQ(plain.world.bottle.displaced_y_m, 0.0);

  std::string bad = kMinimal;
  bad.replace(bad.find("free_turn_deg: 240.0"), 20, "free_turn_deg: 240.0, displaced_mm: [60]");
  std::string e = error_of(bad);
  EXPECT_NE(e.find("bottle.displaced_mm"), std::string::npos) << e;
  bad = kMinimal;
  bad.replace(bad.find("free_turn_deg: 240.0"), 20,
              "free_turn_deg: 240.0, displaced_mm: [0, 5000]");
  e = error_of(bad);
  EXPECT_NE(e.find("5000"), std::string::npos) << e;
  bad = kMinimal;
  bad.replace(bad.find("friction: 0.8"), 13, "friction: 0.8, held_to_tabel: true");
  e = error_of(bad);
  EXPECT_NE(e.find("unknown key 'held_to_tabel' in 'cap' (did you mean 'held_to_table'?)"),
            std::string::npos)
      << e;
}

// Disturbances and fragile objects (docs/rig.md, "Disturbances and fragile objects"): each key
// optional, absent none; a start on the run's clock goes to the world, one timed from a stage waits
// for it; directions are made unit vectors.
TEST(Scenario, DisturbanceAndFragileKeys) {
  const Scenario plain = parse_scenario(kMinimal, "s.yaml");
  const DisturbanceParams& none = plain.world.disturbance;
  EXPECT_EQ(none.pull.force_n, 0.0);
  EXPECT_EQ(none.mass_step.added_kg, 0.0);
  EXPECT_EQ(none.knock.impulse_ns, 0.0);
  EXPECT_FALSE(std::isfinite(none.pull.start_s));
  EXPECT_EQ(plain.world.cap.crush_force_n, 0.0);
  for (const DisturbanceStart& start : plain.disturbance_start)
    EXPECT_TRUE(start.stage.empty());

  std::string text = kMinimal;
  text.replace(text.find("friction: 0.8"), 13, "friction: 0.8, crush_force_n: 1.5");
  text +=
      "disturbance:\n"
      "  pull: {force_n: 0.3, direction: [0, 3, -4], stage: TRANSPORT, start_s: 0.5,"
      " ramp_s: 0.2, duration_s: 1.25}\n"
      "  mass_step: {added_kg: 0.01, start_s: 12}\n"
      "  knock: {impulse_ns: 0.004, direction: [2, 0, 0], stage: LIFT, start_s: 0.25}\n";
  const Scenario s = parse_scenario(text, "s.yaml");
  EXPECT_EQ(s.world.cap.crush_force_n, 1.5);
  const DisturbanceParams& d = s.world.disturbance;
  EXPECT_EQ(d.pull.force_n, 0.3);
  EXPECT_DOUBLE_EQ(d.pull.direction.y, 0.6);
  EXPECT_DOUBLE_EQ(d.pull.direction.z, -0.8);
  EXPECT_EQ(d.pull.ramp_s, 0.2);
  EXPECT_EQ(d.pull.duration_s, 1.25);
  EXPECT_FALSE(std::isfinite(d.pull.start_s)) << "timed from its stage: not started yet";
  const auto start = [&s](DisturbanceKind k) {
    return s.disturbance_start[static_cast<std::size_t>(k)];
  };
  EXPECT_EQ(start(DisturbanceKind::kPull).stage, "TRANSPORT");
  EXPECT_EQ(start(DisturbanceKind::kPull).after_s, 0.5);
  EXPECT_EQ(d.mass_step.added_kg, 0.01);
  EXPECT_EQ(d.mass_step.start_s, 12.0) << "on the run's clock";
  EXPECT_TRUE(start(DisturbanceKind::kMassStep).stage.empty());
  EXPECT_EQ(d.knock.impulse_ns, 0.004);
  EXPECT_EQ(d.knock.direction.x, 1.0);
  EXPECT_EQ(d.knock.duration_s, 0.005) << "the default: a few milliseconds";
  EXPECT_EQ(start(DisturbanceKind::kKnock).stage, "LIFT");
  EXPECT_EQ(start(DisturbanceKind::kKnock).after_s, 0.25);

  // Defaults of the optional keys: the pull straight down, as a step, to the end of the run.
  const Scenario pull_only =
      parse_scenario(kMinimal + "disturbance: {pull: {force_n: 0.1, start_s: 3}}\n", "s.yaml");
  EXPECT_EQ(pull_only.world.disturbance.pull.direction.z, -1.0);
  EXPECT_EQ(pull_only.world.disturbance.pull.ramp_s, 0.0);
  EXPECT_FALSE(std::isfinite(pull_only.world.disturbance.pull.duration_s));
  EXPECT_EQ(pull_only.world.disturbance.pull.start_s, 3.0);
  EXPECT_EQ(pull_only.world.disturbance.knock.impulse_ns, 0.0);
}

TEST(Scenario, BadDisturbanceAndFragileValuesNameKeyAndValue) {
  const struct {
    std::string yaml;
    std::vector<std::string> says;
  } cases[] = {
      {"disturbance: {pull: {force_n: -1, start_s: 1}}\n", {"disturbance.pull.force_n", "-1"}},
      {"disturbance: {pull: {force_n: 0.1}}\n", {"start_s", "missing"}},
      {"disturbance: {pull: {force_n: 0.1, start_s: 1, direction: [0, 0, 0]}}\n",
       {"disturbance.pull.direction", "[0, 0, 0]"}},
      {"disturbance: {pull: {force_n: 0.1, start_s: 1, direction: [1, 0]}}\n",
       {"disturbance.pull.direction", "[x, y, z]"}},
      {"disturbance: {pull: {force_n: 0.1, start_s: 1, ramp_s: -2}}\n",
       {"disturbance.pull.ramp_s", "-2"}},
      {"disturbance: {pull: {force_n: 0.1, start_s: 1, duration_s: 0}}\n",
       {"disturbance.pull.duration_s", "0"}},
      {"disturbance: {pull: {force_n: 0.1, stage: TRANSPROT, start_s: 1}}\n",
       {"disturbance.pull.stage", "TRANSPROT", "did you mean 'TRANSPORT'"}},
      {"disturbance: {mass_step: {added_kg: 5, start_s: 1}}\n",
       {"disturbance.mass_step.added_kg", "5"}},
      {"disturbance: {knock: {impulse_ns: 0.01, start_s: 1, duration_s: 0.5}}\n",
       {"disturbance.knock.duration_s", "0.5"}},
      {"disturbance: {knock: {impulse_ns: 0, start_s: 1}}\n", {"disturbance.knock.impulse_ns"}},
      {"disturbance: {nudge: {impulse_ns: 0.01, start_s: 1}}\n",
       {"unknown key 'nudge' in 'disturbance'"}},
      {"disturbance: {pull: {force: 0.1, start_s: 1}}\n", {"unknown key 'force'", "force_n"}},
  };
  for (const auto& c : cases) {
    const std::string e = error_of(kMinimal + c.yaml);
    EXPECT_NE(e.find("s.yaml:7"), std::string::npos) << c.yaml << e;
    for (const std::string& word : c.says)
      EXPECT_NE(e.find(word), std::string::npos) << c.yaml << " -> " << e;
  }
  std::string crush = kMinimal;
  crush.replace(crush.find("friction: 0.8"), 13, "friction: 0.8, crush_force_n: -3");
  const std::string e = error_of(crush);
  EXPECT_NE(e.find("cap.crush_force_n"), std::string::npos) << e;
  EXPECT_NE(e.find("-3"), std::string::npos) << e;
}

TEST(Scenario, ControllerOverridesAreKept) {
  const Scenario s =
      parse_scenario(kMinimal + "controller: {twist_yaw_rate_rps: 0.25, ns: 6}\n", "s.yaml");
  ASSERT_EQ(s.controller.size(), 2U);
  EXPECT_EQ(s.controller[0].first, "twist_yaw_rate_rps");
  EXPECT_EQ(s.controller[1].second, 6.0);
}

// One list of controller keys: every key the controller's configuration file takes is a
// scenario's override too, and reaches the controller, except those the scenario's world decides.
TEST(Scenario, TakesEveryControllerKeyButThoseItsWorldDecides) {
  const std::set<std::string> world{"task",       "gravity_axis", "cap_x_m",          "cap_y_m",
                                    "bottle_x_m", "bottle_y_m",   "tighten_clockwise"};
  for (const std::string& key : config::controller_config_keys()) {
    // Names, not numbers: ControllerOverridesAreKept, ControllerGripIsANameItKnows.
    if (key == "slip_detector" || key == "grip") continue;
    if (world.contains(key)) {
      EXPECT_NE(error_of(kMinimal + "controller: {" + key + ": 1}\n").find("unknown key"),
                std::string::npos)
          << key;
      continue;
    }
    // Taken by the scenario, and a setting the rig's controller configuration can set.
    const Scenario s = parse_scenario(kMinimal + "controller: {" + key + ": 1}\n", "s.yaml");
    ASSERT_EQ(s.controller.size(), 1U) << key;
    control::Config cfg;
    EXPECT_TRUE(config::set_controller_field(cfg, key, 1.0)) << key;
  }
}

TEST(Scenario, ControllerGripIsANameItKnows) {
  EXPECT_EQ(parse_scenario(kMinimal + "controller: {grip: margin}\n", "s.yaml").grip, "margin");
  EXPECT_EQ(parse_scenario(kMinimal, "s.yaml").grip, "");
  const std::string e = error_of(kMinimal + "controller: {grip: firm}\n");
  EXPECT_NE(e.find("controller.grip"), std::string::npos) << e;
  EXPECT_NE(e.find("paper or margin"), std::string::npos) << e;
}

TEST(Scenario, SensorElementModelIsANameItKnows) {
  EXPECT_EQ(parse_scenario(kMinimal + "sensor: {element_model: feelers}\n", "s.yaml")
                .optics.element_model,
            ElementModel::kFeelers);
  EXPECT_EQ(parse_scenario(kMinimal, "s.yaml").optics.element_model, ElementModel::kGaussian);
  const std::string e = error_of(kMinimal + "sensor: {element_model: conical}\n");
  EXPECT_NE(e.find("s.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("sensor.element_model"), std::string::npos) << e;
  EXPECT_NE(e.find("conical"), std::string::npos) << e;
  EXPECT_NE(e.find("gaussian or feelers"), std::string::npos) << e;
}

// --- a calibration error: sensor.normal_curve_error, shear_curve_error, layout_offset_px --------

// The measurement is given the erred calibration and the sensor renders the true one (docs/rig.md,
// "Calibration error"): a pure normal load of 1 N then reads (1 + normal_curve_error) N on every
// element, and a shear displacement of minus the layout offset.
TEST(ScenarioCalibrationError, TheMeasurementIsGivenTheErredCalibrationTheSensorRendersTheTrue) {
  const Scenario s = parse_scenario(
      kMinimal +
          "sensor: {normal_curve_error: 0.04, shear_curve_error: -0.03, layout_offset_px: [0.25, "
          "-0.5]}\n",
      "s.yaml");
  const auto normals = World(s.world).element_normals();
  const auto truth = rendered_calibrations(s, s.camera, normals);
  const auto given = simulated_calibrations(s, s.camera, normals);
  for (std::size_t i = 0; i < kFingertips; ++i) {
    ASSERT_EQ(given[i].normal_curve.x().size(), truth[i].normal_curve.x().size());
    for (std::size_t j = 0; j < truth[i].normal_curve.x().size(); ++j) {
      EXPECT_EQ(given[i].normal_curve.x()[j], truth[i].normal_curve.x()[j]);
      EXPECT_DOUBLE_EQ(given[i].normal_curve.y()[j], 1.04 * truth[i].normal_curve.y()[j]);
    }
    for (std::size_t j = 0; j < truth[i].shear_curve.x().size(); ++j) {
      EXPECT_EQ(given[i].shear_curve.x()[j], truth[i].shear_curve.x()[j]);
      EXPECT_DOUBLE_EQ(given[i].shear_curve.y()[j], 0.97 * truth[i].shear_curve.y()[j]);
    }
    for (std::size_t k = 0; k < truth[i].elements.size(); ++k) {
      EXPECT_DOUBLE_EQ(given[i].elements[k].center_px.x, truth[i].elements[k].center_px.x + 0.25);
      EXPECT_DOUBLE_EQ(given[i].elements[k].center_px.y, truth[i].elements[k].center_px.y - 0.5);
      EXPECT_DOUBLE_EQ(given[i].elements[k].zero_px.x, truth[i].elements[k].zero_px.x + 0.25);
      EXPECT_DOUBLE_EQ(given[i].elements[k].zero_px.y, truth[i].elements[k].zero_px.y - 0.5);
    }
  }
  // The world's shear law is the sensor's true curve, not the erred one.
  EXPECT_EQ(s.world.fingertip.shear_curve.odd(0.05), truth[0].shear_curve.odd(0.05));

  SimulatedSensors sensors(s, s.camera, normals);
  EXPECT_EQ(sensors.calibrations()[0].elements[3].center_px.x, given[0].elements[3].center_px.x);
  Extractor ex(sensors.calibrations()[0]);
  ex.begin_reference();
  ReferenceResult ref{};
  for (int k = 0; k < s.optics.reference_frames; ++k)
    ref = ex.add_reference_frame(sensors.render(0, FingertipTruth{}).view());
  ASSERT_EQ(ref.status, ReferenceStatus::kComplete);
  FingertipTruth load{};
  for (ElementTruth& e : load.elements)
    e.fz_n = 1.0;
  ASSERT_EQ(ex.measure(sensors.render(0, load).view(), {1, 0}), MeasureStatus::kOk);
  double fz_sum = 0;
  for (const ElementReading& m : ex.readings()) {
    ASSERT_TRUE(m.contact) << m.id;
    EXPECT_NEAR(m.fz, 1.04, 0.03) << m.id;
    EXPECT_NEAR(m.ux_mm, -0.25 * s.optics.mm_per_px, 0.0015) << m.id;
    EXPECT_NEAR(m.uy_mm, 0.5 * s.optics.mm_per_px, 0.0015) << m.id;
    fz_sum += m.fz;
  }
  EXPECT_NEAR(fz_sum / static_cast<double>(ex.readings().size()), 1.04, 0.005);

  // Without the keys the measurement is given the sensor's own calibration.
  const Scenario exact = parse_scenario(kMinimal, "s.yaml");
  const auto exact_given = simulated_calibrations(exact, exact.camera, normals);
  const auto exact_truth = rendered_calibrations(exact, exact.camera, normals);
  EXPECT_EQ(exact_given[1].normal_curve.y()[2], exact_truth[1].normal_curve.y()[2]);
  EXPECT_EQ(exact_given[1].elements[40].zero_px.y, exact_truth[1].elements[40].zero_px.y);
}

TEST(ScenarioCalibrationError, BadValuesNameFileKeyAndValue) {
  struct Bad {
    const char* sensor;
    const char* key;
    const char* value;
  };
  const Bad bad[] = {
      {"normal_curve_error: 0.7", "sensor.normal_curve_error", "0.7"},
      {"shear_curve_error: -0.51", "sensor.shear_curve_error", "-0.51"},
      {"layout_offset_px: [6, 0]", "sensor.layout_offset_px", "6"},
      {"layout_offset_px: [0, -5.5]", "sensor.layout_offset_px", "-5.5"},
      {"layout_offset_px: [1]", "sensor.layout_offset_px", "[dx, dy]"},
  };
  for (const Bad& b : bad) {
    const std::string e = error_of(kMinimal + "sensor: {" + b.sensor + "}\n");
    EXPECT_NE(e.find("s.yaml"), std::string::npos) << e;
    EXPECT_NE(e.find(b.key), std::string::npos) << e;
    EXPECT_NE(e.find(b.value), std::string::npos) << e;
  }
}

// --- a lab's sensor: sensor.calibration (docs/rig.md, "A lab's sensor") ------------------------

// A lab's file: the rig's own sensor scaled to a 352 x 352 camera (the sample set's), its normals
// the world's.
Calibration lab_calibration() {
  CameraParams cam;
  cam.width = 352;
  cam.height = 352;
  return make_calibration("lab", cam, SensorOpticsParams{}, World(WorldParams{}).element_normals());
}

// A file written into the test's own temporary folder.
std::filesystem::path lab_file(const std::string& name, const Calibration& cal) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "lab_sensor";
  std::filesystem::create_directories(dir);
  config::save_calibration(dir / name, cal);
  return dir / name;
}

std::string lab_scenario(const std::string& calibration, const std::string& camera_size) {
  std::string text = kMinimal;
  text.replace(text.find("width: 640, height: 480"), 23, camera_size);
  return text + "sensor: {calibration: '" + calibration + "'}\n";
}

TEST(ScenarioLabSensor, TheFileIsTheSensorBothFingertipsRenderAndTheShearLaw) {
  Calibration lab = lab_calibration();
  lab.shear_curve = PiecewiseLinear({0.0, 0.03, 0.09}, {0.0, 0.06, 0.5});
  lab.noise_floor = 7.5;
  const std::filesystem::path file = lab_file("lab.yaml", lab);
  const Scenario s =
      parse_scenario(lab_scenario(file.string(), "width: 352, height: 352"), "s.yaml");
  ASSERT_TRUE(s.calibration);
  EXPECT_EQ(s.calibration_file, file);
  EXPECT_EQ(s.world.fingertip.shear_curve.odd(0.05), lab.shear_curve.odd(0.05));
  const auto cals = simulated_calibrations(s, s.camera, World(s.world).element_normals());
  for (std::size_t i = 0; i < kFingertips; ++i) {
    EXPECT_EQ(cals[i].sensor_id, kFingertipIds[i]);
    EXPECT_EQ(cals[i].width, 352);
    EXPECT_EQ(cals[i].noise_floor, 7.5);
    ASSERT_EQ(cals[i].elements.size(), lab.elements.size());
    for (std::size_t k = 0; k < lab.elements.size(); ++k) {
      EXPECT_EQ(cals[i].elements[k].center_px.x, lab.elements[k].center_px.x) << k;
      EXPECT_EQ(cals[i].elements[k].center_px.y, lab.elements[k].center_px.y) << k;
    }
  }
  // A relative path is the scenario file's neighbour.
  const std::filesystem::path scenario = file.parent_path() / "lab-scenario.yaml";
  util::write_file_atomic(scenario, lab_scenario("lab.yaml", "width: 352, height: 352"));
  EXPECT_EQ(load_scenario(scenario).calibration_file, file);
  // Without the key: the rig's own sensor, as before.
  EXPECT_FALSE(parse_scenario(kMinimal, "s.yaml").calibration);
}

TEST(ScenarioLabSensor, FilesTheFingertipCannotRenderAreRefusedNamingFileKeyAndValue) {
  const std::string size = "width: 352, height: 352";
  // Missing.
  const std::string missing =
      (std::filesystem::path(::testing::TempDir()) / "no-such.yaml").string();
  std::string e = error_of(lab_scenario(missing, size));
  EXPECT_NE(e.find("s.yaml:7: key 'sensor.calibration'"), std::string::npos) << e;
  EXPECT_NE(e.find(missing + ": cannot open"), std::string::npos) << e;

  // Another element count.
  Calibration fewer = lab_calibration();
  fewer.elements.pop_back();
  const std::string fewer_file = lab_file("fewer.yaml", fewer).string();
  e = error_of(lab_scenario(fewer_file, size));
  EXPECT_NE(e.find("key 'sensor.calibration'"), std::string::npos) << e;
  EXPECT_NE(e.find(fewer_file + ": key 'elements': must hold the rig fingertip's 41 elements"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("holds 40"), std::string::npos) << e;

  // A normal on another ring: element 12 (ring 2, polar 20 degrees) looking along the axis.
  Calibration tilted = lab_calibration();
  tilted.elements[12].normal = {0.0, 0.0, 1.0};
  const std::string tilted_file = lab_file("tilted.yaml", tilted).string();
  e = error_of(lab_scenario(tilted_file, size));
  EXPECT_NE(e.find(tilted_file + ": key 'elements[12].normal': (element id 12) is [0, 0, 1], 20 " +
                   "deg from the rig fingertip's element 12"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("at most 5 deg"), std::string::npos) << e;
  // Within the tolerance: taken (element 12 turned 10 degrees about the axis is 3.4 degrees off).
  Calibration turned = lab_calibration();
  Vec3& n = turned.elements[12].normal;
  const double a = 10.0 * std::numbers::pi / 180.0;
  n = {n.x * std::cos(a) - n.y * std::sin(a), n.x * std::sin(a) + n.y * std::cos(a), n.z};
  EXPECT_NO_THROW(
      check_lab_calibration(turned, "turned.yaml", World(WorldParams{}).element_normals()));

  // The camera's image is the file's, not overridden.
  const std::string lab = lab_file("lab.yaml", lab_calibration()).string();
  e = error_of(lab_scenario(lab, "width: 640, height: 352"));
  EXPECT_NE(e.find("s.yaml:3: key 'camera.width': must be the calibration's image.width, 352 (" +
                   lab + "), is '640'"),
            std::string::npos)
      << e;
  // The sensor keys the file sets are refused beside it.
  e = error_of(kMinimal + "sensor: {calibration: '" + lab + "', mm_per_px: 0.03}\n");
  EXPECT_NE(e.find("key 'sensor.mm_per_px': is the calibration file's"), std::string::npos) << e;
}

}  // namespace
}  // namespace tactile::rig
