#pragma once

// The random scenario sweep (docs/slip.md, "The sweep"): N scenarios drawn from documented ranges,
// each run in lockstep by a child `rig` process, scored from its report.json into one CSV row per
// scenario and decision method, a summary table and a plot. The draw is deterministic per
// (sweep seed, scenario index), so shards and job counts never change a scenario.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/rig/scenario.hpp"

namespace tactile::rig::sweep {

// A closed interval a drawn parameter lies in.
struct Range {
  double lo = 0;
  double hi = 0;
};

// The documented ranges (docs/slip.md): every draw lies within them, ends included.
struct Ranges {
  Range mass_kg{0.003, 0.080};
  Range radius_mm{12.0, 20.0};
  Range friction{0.4, 1.2};
  Range kinetic_ratio{0.3, 0.9};
  Range free_turn_deg{90.0, 540.0};
  Range vibration_mm{0.0, 0.7};
  Range vibration_hz{5.0, 20.0};
  Range noise_sigma{1.0, 5.0};
  Range fps{60.0, 500.0};
  // bit_depth: 8 or 16, each with probability 1/2.
};
inline constexpr Ranges kRanges{};

// The negative cases of the classifications (docs/slip.md, "Negative cases"): in every block of
// 10 consecutive indices (0-9, 10-19, ...) one scenario has its bottle displaced and another its
// cap held to the table, at places drawn per (sweep seed, block).
enum class Case : std::uint8_t { kNormal, kBottleDisplaced, kCapHeld };
// "normal", "bottle_displaced", "cap_held": the CSV's `case` and the report's `case`.
const char* to_string(Case c);
inline constexpr std::uint64_t kCaseBlock = 10;
// The bottle's displacement from the controller's place: this far, in one of 8 directions.
inline constexpr Range kDisplacementMm{60.0, 120.0};
// The lowest wrist height of the lowering (controller.lower_limit_m) in a displaced-bottle case:
// the default, 0, lowers the cap onto the table, which is a support too.
inline constexpr double kDisplacedLowerLimitM = 0.09;

// The disturbances and fragile objects of the sweep (docs/slip.md, "Disturbances and fragile
// objects"), drawn from a generator of their own per (sweep seed, index), so that every other value
// of a scenario is what it was before they were drawn. A share of the scenarios gets one
// disturbance, of a kind drawn with equal chances, timed from the carry (TRANSPORT); another,
// independent share is fragile.
enum class Disturbance : std::uint8_t { kNone, kPullStep, kPullRamp, kMassStep, kKnock };
// "none", "pull_step", "pull_ramp", "mass_step", "knock": the CSV's `disturbance`.
const char* to_string(Disturbance d);
inline constexpr double kDisturbedShare = 1.0 / 3.0;
inline constexpr double kFragileShare = 1.0 / 5.0;
// The stage a disturbance is timed from, and its time into it.
inline constexpr const char* kDisturbanceStage = "TRANSPORT";
inline constexpr Range kDisturbanceAfterS{0.1, 1.0};
// A pull: this many times the cap's weight, for this long; a ramp rises over ramp_s.
inline constexpr Range kPullWeights{0.5, 2.0};
inline constexpr Range kPullDurationS{0.3, 1.5};
inline constexpr Range kPullRampS{0.1, 0.5};
// A mass step: this many times the cap's mass added.
inline constexpr Range kMassStepMasses{0.5, 2.0};
// A knock: the cap's mass times this change of speed (m/s), over kKnockDurationS.
inline constexpr Range kKnockSpeedMps{0.05, 0.3};
inline constexpr double kKnockDurationS = 0.005;
// A fragile object's crush force: this many times its least holding force (hold_need's
// grip_needed_N, the disturbance included).
inline constexpr Range kCrushOverNeed{2.0, 6.0};

// The sensor every scenario of a sweep sees (`rig --sweep --sensor NAME`, docs/slip.md): kRig,
// the rig's own (the Gaussian spot; the files say nothing of the sensor), kFeelers, the paper's
// feeler element on every scenario (sensor.element_model: feelers), or kDrawn, a sensor drawn per
// scenario (DrawnSensor below). Nothing else of the draw changes.
enum class SensorSet { kRig, kFeelers, kDrawn };
std::optional<SensorSet> sensor_set_from_string(std::string_view name);
// The names sensor_set_from_string accepts, for error messages.
inline constexpr const char* kSensorSetNames = "rig, feelers or drawn";

// The drawn sensor's ranges (SensorSet::kDrawn; docs/slip.md, "The drawn sensor").
inline constexpr double kFeelerShare = 0.5;         // the paper's feeler element, else Gaussian
inline constexpr Range kStiffnessNPerMm{1.0, 2.5};  // fingertip.normal_stiffness_n_per_mm
inline constexpr Range kSpotScale{0.8, 1.25};       // times the spot's sigma_min and sigma_max
inline constexpr double kShotNoiseShare = 0.5;      // shot noise, else read noise alone
inline constexpr Range kShotNoiseGain{5.0, 50.0};   // camera.shot_noise_gain, e- per level
inline constexpr Range kCurveError{-0.05, 0.05};    // sensor.normal_ and shear_curve_error
inline constexpr Range kLayoutOffsetPx{-0.5, 0.5};  // sensor.layout_offset_px, each axis

// One drawn sensor: from a generator of its own, drawn for every scenario whatever the set (the
// draw's other values are untouched by it), written into the file only for SensorSet::kDrawn.
struct DrawnSensor {
  bool feelers = false;
  double normal_stiffness_n_per_mm = 0;
  double spot_scale = 0;
  double shot_noise_gain = 0;  // 0: none
  double normal_curve_error = 0;
  double shear_curve_error = 0;
  double layout_offset_x_px = 0;
  double layout_offset_y_px = 0;
};

// One drawn scenario. Values are rounded to a fixed grid (0.1 g, 0.01 mm, 0.001, 0.1 deg, 1 um,
// 0.01 Hz, 0.01 levels, whole fps) so that the scenario file states them exactly.
struct Draw {
  std::uint64_t index = 0;
  std::uint64_t scenario_seed = 0;  // the scenario file's `seed` (noise), mixed from (S, index)
  double mass_kg = 0;
  double radius_mm = 0;
  double friction = 0;
  double kinetic_ratio = 0;
  double free_turn_deg = 0;
  double vibration_mm = 0;
  double vibration_hz = 0;
  double noise_sigma = 0;
  int fps = 0;
  int bit_depth = 0;
  Case scenario_case = Case::kNormal;
  // Drawn for every scenario (after the values above, which they leave unchanged), used by
  // kBottleDisplaced: bottle.displaced_mm.
  double displaced_x_mm = 0;
  double displaced_y_mm = 0;
  // From the disturbances' own generator (kDisturbedShare, kFragileShare above).
  Disturbance disturbance = Disturbance::kNone;
  double pull_n = 0;           // kPullStep, kPullRamp
  double pull_ramp_s = 0;      // kPullRamp
  double pull_duration_s = 0;  // kPullStep, kPullRamp
  double added_kg = 0;         // kMassStep
  double impulse_ns = 0;       // kKnock
  // The pull's or the knock's direction (world frame): one of 8 azimuths, horizontal, 45 degrees
  // down or straight down.
  std::array<double, 3> direction{0, 0, -1};
  double after_s = 0;        // into kDisturbanceStage
  double crush_force_n = 0;  // 0: not fragile
  // Not drawn: the sweep's sensor set (SweepOptions::sensor), and a lab's sensor
  // (SweepOptions::lab_sensor): the camera's image becomes the file's, the bit depth drawn above
  // unused, and the file says sensor.calibration.
  SensorSet sensor = SensorSet::kRig;
  std::optional<LabSensor> lab_sensor;
  DrawnSensor drawn_sensor;
};

// Scenario `index` of the sweep with seed `sweep_seed`: depends on nothing else. Pure.
Draw draw_scenario(std::uint64_t sweep_seed, std::uint64_t index);

// The drawn scenario as a scenario file (tactile-scenario/1), the controller's defaults (no
// `controller` section, except lower_limit_m in a displaced-bottle case). max_sim_time_s > 0
// writes sim.max_time_s (short test sweeps).
std::string scenario_yaml(const Draw& d, double max_sim_time_s = 0);

// --- the table ---------------------------------------------------------------------------------

// The CSV's columns, in order (docs/slip.md lists their meaning).
const std::vector<std::string>& columns();

// One row: a cell per column, as written in the CSV ("" for none).
struct Row {
  std::vector<std::string> cells;
  const std::string& at(const std::string& column) const;
  // The cell as a number; NaN when empty or not a number.
  double number(const std::string& column) const;
};

// The row of one scenario's run: its method is the slip detector the controller ran (the report's
// `slip.detector`; "paper" for a report without it), from the report's JSON text. Throws
// std::runtime_error for a report that is not JSON or lacks a key.
std::vector<Row> rows_from_report(const Draw& d, const std::string& report_json);
// The row of a scenario whose rig process (run with detector `method`) failed: its exit status
// (128 + signal when killed) and the last line it wrote on standard error.
Row failed_row(const Draw& d, const std::string& method, int exit_status,
               const std::string& last_stderr_line);

// The CSV text: a header line, then the rows (sorted by index, then method).
std::string csv_text(std::vector<Row> rows);
// Parses csv_text()'s output; throws std::runtime_error naming `source` and the line.
std::vector<Row> parse_csv(const std::string& text, const std::string& source);

// What a sweep directory holds besides its rows (DIR/sweep.json).
struct SweepInfo {
  std::uint64_t seed = 0;
  std::uint64_t scenarios = 0;  // N drawn, over all shards
  double max_sim_time_s = 0;    // 0: the scenarios' own limit
  std::string calibration;      // a lab's sensor (--calibration, absolute); empty: the rig's
  int shard = 1;                // K of shards
  int shards = 1;
  bool stopped = false;  // stopped by a signal before every scenario ran
};
std::string info_json(const SweepInfo& info);
SweepInfo parse_info(const std::string& text, const std::string& source);

// The summary (Markdown): per method, median, 5th and 95th percentile of each score, completion,
// drops, classifications. Depends on the rows and the seed, N and time limit only.
std::string summary_markdown(const std::vector<Row>& rows, const SweepInfo& info);
// The distributions as a PNG drawn with tactile::plot.
void write_plot(const std::vector<Row>& rows, const SweepInfo& info,
                const std::filesystem::path& png);

// --- running -----------------------------------------------------------------------------------

struct SweepOptions {
  std::uint64_t scenarios = 0;
  std::uint64_t seed = 1;
  std::filesystem::path out;
  int jobs = 0;  // 0: the number of cores
  int shard = 1;
  int shards = 1;
  double max_sim_time_s = 0;
  // Each scenario runs once per slip detector named here (control::to_string names), with
  // `--slip-detector NAME`: one row per scenario and detector.
  std::vector<std::string> detectors{"paper", "field", "learned"};
  // Every run's grip (`--grip NAME`, control::to_string names); empty: the scenario's.
  std::string grip;
  // The sensor every scenario sees (`--sensor NAME`).
  SensorSet sensor = SensorSet::kRig;
  // A lab's sensor every scenario renders (`--calibration FILE`, rig::load_lab_sensor).
  std::optional<LabSensor> lab_sensor;
  // Keep the runs whose reports `out` holds from an earlier run of this sweep (one a signal or a
  // kill cut short; its scenario file must be this draw's) and run only the others.
  bool resume = false;
  // The program run per scenario as PROGRAM --lockstep --scenario FILE --report FILE; empty: this
  // rig (/proc/self/exe).
  std::string child_program;
};

// The scenario indices of shard K of N: i with i % N == K - 1 (interleaved, so the shards get
// alike shares of every kind of scenario).
std::vector<std::uint64_t> shard_indices(std::uint64_t scenarios, int shard, int shards);

// "K/N" (1 <= K <= N) as {K, N}: --shard of rig --sweep and slip_train. Throws
// std::invalid_argument saying what is wrong with `text`.
struct Shard {
  int shard = 1;
  int shards = 1;
};
Shard parse_shard(const std::string& text);

// Runs the sweep (or its shard) and writes DIR/scenarios/, DIR/reports/, DIR/logs/, sweep.json,
// sweep.csv, summary.md and sweep.png; prints the summary on standard output and the progress on
// standard error. A SIGINT or SIGTERM (util::install_stop_handlers) stops the children and writes
// what is done. Returns the number of rows written.
std::size_t run_sweep(const SweepOptions& options);

// Combines the sweep directories `dirs` (shards of one sweep: same seed, N and time limit, no
// scenario twice) into `out`: sweep.csv, summary.md and sweep.png as one run would have written
// them. Throws std::runtime_error naming the directory for a mismatch.
std::size_t merge_sweeps(const std::vector<std::filesystem::path>& dirs,
                         const std::filesystem::path& out);

}  // namespace tactile::rig::sweep
