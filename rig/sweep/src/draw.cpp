// The sweep's draw: pure, no I/O (docs/slip.md, "The sweep").
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "tactile/rig/scenario.hpp"
#include "tactile/rig/sweep.hpp"
#include "tactile/rig/world.hpp"
#include "tactile/util/random.hpp"

namespace tactile::rig::sweep {
namespace {

// Uniform in the range, on a grid of `step`, kept within the range's ends.
double on_grid(util::Random& rng, Range r, double step) {
  const double lo = std::ceil(r.lo / step - 1e-9);
  const double hi = std::floor(r.hi / step + 1e-9);
  const double k = lo + std::floor(rng.uniform() * (hi - lo + 1.0));
  return std::fmin(k, hi) * step;
}

// Which index of a block of kCaseBlock is displaced and which is held: two different ones, from
// the block's own generator.
Case case_of(std::uint64_t sweep_seed, std::uint64_t index) {
  constexpr std::uint64_t kSalt = 0x6e65676174697665ULL;  // "negative"
  util::Random rng(util::splitmix64(util::splitmix64(sweep_seed ^ kSalt) ^ (index / kCaseBlock)));
  const std::uint64_t displaced = rng.below(kCaseBlock);
  const std::uint64_t held = (displaced + 1 + rng.below(kCaseBlock - 1)) % kCaseBlock;
  const std::uint64_t at = index % kCaseBlock;
  return at == displaced ? Case::kBottleDisplaced : at == held ? Case::kCapHeld : Case::kNormal;
}

// Rounded to a grid of 1 / `per_unit` (a whole number of steps over an exact power of ten, so the
// file's shortest text is the grid's: 1.3879, not 1.3879000000000001).
double rounded(double v, double per_unit) {
  return std::round(v * per_unit) / per_unit;
}

// The disturbance and the fragility of scenario `index` (Draw's last values), from a generator of
// their own: the draw's main generator, and so every other value, is untouched by them.
void draw_disturbance(std::uint64_t sweep_seed, std::uint64_t index, Draw& d) {
  constexpr std::uint64_t kSalt = 0x6469737475726221ULL;  // "disturb!"
  util::Random rng(util::splitmix64(util::splitmix64(sweep_seed ^ kSalt) ^ index));
  // Every number is drawn whatever the outcome, in a fixed order.
  const bool disturbed = rng.uniform() < kDisturbedShare;
  const auto kind = static_cast<Disturbance>(1 + rng.below(4));
  const double weights = on_grid(rng, {kPullWeights.lo * 100, kPullWeights.hi * 100}, 1.0) / 100;
  const double masses =
      on_grid(rng, {kMassStepMasses.lo * 100, kMassStepMasses.hi * 100}, 1.0) / 100;
  const double speed =
      on_grid(rng, {kKnockSpeedMps.lo * 1000, kKnockSpeedMps.hi * 1000}, 1.0) / 1000;
  const double duration =
      on_grid(rng, {kPullDurationS.lo * 100, kPullDurationS.hi * 100}, 1.0) / 100;
  const double ramp = on_grid(rng, {kPullRampS.lo * 100, kPullRampS.hi * 100}, 1.0) / 100;
  const double after =
      on_grid(rng, {kDisturbanceAfterS.lo * 100, kDisturbanceAfterS.hi * 100}, 1.0) / 100;
  const double azimuth = static_cast<double>(rng.below(8)) * std::numbers::pi / 4.0;
  const double elevation = -static_cast<double>(rng.below(3)) * std::numbers::pi / 4.0;
  const bool fragile = rng.uniform() < kFragileShare;
  const double crush = on_grid(rng, {kCrushOverNeed.lo * 100, kCrushOverNeed.hi * 100}, 1.0) / 100;

  if (disturbed) {
    d.disturbance = kind;
    d.after_s = after;
    // + 0.0: no negative zero in the file.
    d.direction = {rounded(std::cos(elevation) * std::cos(azimuth), 1e4) + 0.0,
                   rounded(std::cos(elevation) * std::sin(azimuth), 1e4) + 0.0,
                   rounded(std::sin(elevation), 1e4) + 0.0};
    const double weight_n = d.mass_kg * 9.81;
    switch (kind) {
      case Disturbance::kPullRamp:
        d.pull_ramp_s = ramp;
        [[fallthrough]];
      case Disturbance::kPullStep:
        d.pull_n = rounded(weights * weight_n, 1e6);
        d.pull_duration_s = duration;
        break;
      case Disturbance::kMassStep:
        d.added_kg = rounded(masses * d.mass_kg, 1e5);
        break;
      case Disturbance::kKnock:
        d.impulse_ns = rounded(speed * d.mass_kg, 1e7);
        break;
      case Disturbance::kNone:
        break;
    }
  }
  if (fragile) {
    // The least holding force of this very scenario, disturbance included: its file's world.
    const Scenario sc = parse_scenario(scenario_yaml(d), "the sweep's draw");
    d.crush_force_n = std::max(1e-3, rounded(crush * hold_need(sc.world, 2.5).grip_needed_n, 1e4));
  }
}

// The drawn sensor of scenario `index` (Draw's drawn_sensor), from a generator of its own: every
// other value of the draw is untouched by it. Every number is drawn, in a fixed order.
DrawnSensor draw_sensor(std::uint64_t sweep_seed, std::uint64_t index) {
  constexpr std::uint64_t kSalt = 0x73656e736f722121ULL;  // "sensor!!"
  util::Random rng(util::splitmix64(util::splitmix64(sweep_seed ^ kSalt) ^ index));
  // On a grid of 1 / per_unit (whole steps over an exact power of ten: the file states it exactly).
  const auto grid = [&](Range r, double per_unit) {
    return on_grid(rng, {r.lo * per_unit, r.hi * per_unit}, 1.0) / per_unit;
  };
  DrawnSensor s;
  s.feelers = rng.uniform() < kFeelerShare;
  s.normal_stiffness_n_per_mm = grid(kStiffnessNPerMm, 100);
  s.spot_scale = grid(kSpotScale, 100);
  const bool shot = rng.uniform() < kShotNoiseShare;
  const double gain = grid(kShotNoiseGain, 10);
  s.shot_noise_gain = shot ? gain : 0.0;
  s.normal_curve_error = grid(kCurveError, 1000);
  s.shear_curve_error = grid(kCurveError, 1000);
  s.layout_offset_x_px = grid(kLayoutOffsetPx, 100);
  s.layout_offset_y_px = grid(kLayoutOffsetPx, 100);
  return s;
}

// The disturbance's section of the scenario file.
std::string disturbance_yaml(const Draw& d) {
  const std::string direction =
      fmt::format("[{}, {}, {}]", d.direction[0], d.direction[1], d.direction[2]);
  const std::string start = fmt::format("stage: {}, start_s: {}", kDisturbanceStage, d.after_s);
  switch (d.disturbance) {
    case Disturbance::kPullStep:
      return fmt::format(
          "disturbance: {{pull: {{force_n: {}, direction: {}, {}, duration_s: {}}}}}\n", d.pull_n,
          direction, start, d.pull_duration_s);
    case Disturbance::kPullRamp:
      return fmt::format(
          "disturbance: {{pull: {{force_n: {}, direction: {}, {}, ramp_s: {}, duration_s: {}}}}}\n",
          d.pull_n, direction, start, d.pull_ramp_s, d.pull_duration_s);
    case Disturbance::kMassStep:
      return fmt::format("disturbance: {{mass_step: {{added_kg: {}, {}}}}}\n", d.added_kg, start);
    case Disturbance::kKnock:
      return fmt::format(
          "disturbance: {{knock: {{impulse_ns: {}, direction: {}, {}, duration_s: {}}}}}\n",
          d.impulse_ns, direction, start, kKnockDurationS);
    case Disturbance::kNone:
      break;
  }
  return {};
}

}  // namespace

const char* to_string(Disturbance d) {
  switch (d) {
    case Disturbance::kNone:
      return "none";
    case Disturbance::kPullStep:
      return "pull_step";
    case Disturbance::kPullRamp:
      return "pull_ramp";
    case Disturbance::kMassStep:
      return "mass_step";
    case Disturbance::kKnock:
      return "knock";
  }
  return "?";
}

const char* to_string(Case c) {
  switch (c) {
    case Case::kNormal:
      return "normal";
    case Case::kBottleDisplaced:
      return "bottle_displaced";
    case Case::kCapHeld:
      return "cap_held";
  }
  return "?";
}

Draw draw_scenario(std::uint64_t sweep_seed, std::uint64_t index) {
  // Every value comes from this scenario's own generator, in a fixed order: scenario i is the
  // same whatever else the sweep runs.
  // splitmix64 twice: neighbouring (seed, index) pairs give unrelated generators.
  util::Random rng(util::splitmix64(util::splitmix64(sweep_seed) ^ index));
  const Ranges& r = kRanges;
  Draw d;
  d.index = index;
  d.scenario_seed = rng.next() >> 33;  // small enough for a YAML integer
  d.mass_kg = on_grid(rng, {r.mass_kg.lo * 1e4, r.mass_kg.hi * 1e4}, 1.0) / 1e4;
  d.radius_mm = on_grid(rng, {r.radius_mm.lo * 100, r.radius_mm.hi * 100}, 1.0) / 100;
  d.friction = on_grid(rng, {r.friction.lo * 1000, r.friction.hi * 1000}, 1.0) / 1000;
  d.kinetic_ratio =
      on_grid(rng, {r.kinetic_ratio.lo * 1000, r.kinetic_ratio.hi * 1000}, 1.0) / 1000;
  d.free_turn_deg = on_grid(rng, {r.free_turn_deg.lo * 10, r.free_turn_deg.hi * 10}, 1.0) / 10;
  d.vibration_mm = on_grid(rng, {r.vibration_mm.lo * 1000, r.vibration_mm.hi * 1000}, 1.0) / 1000;
  d.vibration_hz = on_grid(rng, {r.vibration_hz.lo * 100, r.vibration_hz.hi * 100}, 1.0) / 100;
  d.noise_sigma = on_grid(rng, {r.noise_sigma.lo * 100, r.noise_sigma.hi * 100}, 1.0) / 100;
  d.fps = static_cast<int>(on_grid(rng, r.fps, 1.0));
  d.bit_depth = rng.below(2) == 0 ? 8 : 16;
  d.scenario_case = case_of(sweep_seed, index);
  const double distance = on_grid(rng, kDisplacementMm, 1.0);
  const double direction = static_cast<double>(rng.below(8)) * std::numbers::pi / 4.0;
  // On a 0.1 mm grid, so that the file states it exactly.
  d.displaced_x_mm = std::round(distance * std::cos(direction) * 10.0) / 10.0 + 0.0;
  d.displaced_y_mm = std::round(distance * std::sin(direction) * 10.0) / 10.0 + 0.0;
  draw_disturbance(sweep_seed, index, d);
  d.drawn_sensor = draw_sensor(sweep_seed, index);
  return d;
}

std::optional<SensorSet> sensor_set_from_string(std::string_view name) {
  if (name == "rig") return SensorSet::kRig;
  if (name == "feelers") return SensorSet::kFeelers;
  if (name == "drawn") return SensorSet::kDrawn;
  return std::nullopt;
}

std::string scenario_yaml(const Draw& d, double max_sim_time_s) {
  // The camera's image: the rig's 640 x 480 at the drawn depth, or a lab's sensor's own.
  const LabSensor image = d.lab_sensor.value_or(LabSensor{"", 640, 480, d.bit_depth});
  // {} writes the shortest text that reads back as the same double: the file is the draw.
  std::string y = fmt::format(
      "# Scenario {} of a random sweep (docs/slip.md): rig --lockstep --scenario THIS_FILE\n"
      "format: tactile-scenario/1\n"
      "seed: {}\n"
      "camera: {{fps: {}, width: {}, height: {}, bit_depth: {}, noise_sigma: {}}}\n"
      "cap: {{mass_kg: {}, radius_mm: {}, friction: {}, kinetic_ratio: {}}}\n"
      "bottle: {{free_turn_deg: {}}}\n"
      "arm: {{vibration_mm: {}, vibration_hz: {}}}\n",
      d.index, d.scenario_seed, d.fps, image.width, image.height, image.bit_depth, d.noise_sigma,
      d.mass_kg, d.radius_mm, d.friction, d.kinetic_ratio, d.free_turn_deg, d.vibration_mm,
      d.vibration_hz);
  if (d.scenario_case == Case::kCapHeld) {
    y += "# Negative case: the cap is held to the table; no grasp may be classified on the lift.\n";
    y.replace(y.find("kinetic_ratio: "), 0, "held_to_table: true, ");
  }
  if (d.scenario_case == Case::kBottleDisplaced) {
    y += "# Negative case: the bottle stands away from the controller's place; no release may be\n"
         "# classified, the fingers may not open. MOVE5 stops above the table (also a support).\n";
    y.replace(y.find("free_turn_deg: "), 0,
              fmt::format("displaced_mm: [{}, {}], ", d.displaced_x_mm, d.displaced_y_mm));
    y += fmt::format("controller: {{lower_limit_m: {}}}\n", kDisplacedLowerLimitM);
  }
  if (max_sim_time_s > 0) y += fmt::format("sim: {{max_time_s: {}}}\n", max_sim_time_s);
  std::vector<std::string> sensor;
  if (d.sensor == SensorSet::kFeelers) sensor.emplace_back("element_model: feelers");
  if (d.sensor == SensorSet::kDrawn) {
    const DrawnSensor& ds = d.drawn_sensor;
    const SensorOpticsParams rig;  // the rig's spot widths, scaled
    if (ds.shot_noise_gain > 0) {
      y.replace(y.find("noise_sigma: "), 0,
                fmt::format("shot_noise_gain: {}, ", ds.shot_noise_gain));
    }
    y +=
        fmt::format("fingertip: {{normal_stiffness_n_per_mm: {}}}\n", ds.normal_stiffness_n_per_mm);
    sensor.emplace_back(ds.feelers ? "element_model: feelers" : "element_model: gaussian");
    sensor.push_back(fmt::format("spot_sigma_min_px: {}, spot_sigma_max_px: {}",
                                 rounded(rig.spot_sigma_min_px * ds.spot_scale, 1e4),
                                 rounded(rig.spot_sigma_max_px * ds.spot_scale, 1e4)));
    sensor.push_back(fmt::format("normal_curve_error: {}, shear_curve_error: {}",
                                 ds.normal_curve_error, ds.shear_curve_error));
    sensor.push_back(
        fmt::format("layout_offset_px: [{}, {}]", ds.layout_offset_x_px, ds.layout_offset_y_px));
  }
  if (d.lab_sensor) {
    // Single-quoted: a path is any text, and YAML's single quotes escape only themselves.
    std::string path;
    for (const char c : d.lab_sensor->calibration)
      path += c == '\'' ? std::string("''") : std::string(1, c);
    sensor.push_back("calibration: '" + path + "'");
  }
  if (!sensor.empty()) y += fmt::format("sensor: {{{}}}\n", fmt::join(sensor, ", "));
  // The disturbance and the fragility last, so that a file without them is the draw's without.
  if (d.disturbance != Disturbance::kNone) {
    y += fmt::format("# Disturbance ({}): timed from the carry (docs/slip.md).\n",
                     to_string(d.disturbance));
    y += disturbance_yaml(d);
  }
  if (d.crush_force_n > 0) {
    y += "# Fragile: the cap breaks under a grip above crush_force_n per fingertip.\n";
    y.replace(y.find("kinetic_ratio: "), 0, fmt::format("crush_force_n: {}, ", d.crush_force_n));
  }
  return y;
}

}  // namespace tactile::rig::sweep
