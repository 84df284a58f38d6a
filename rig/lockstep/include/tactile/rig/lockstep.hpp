#pragma once

// The lockstep runner (docs/rig.md, "Lockstep runner and report"): the scenario in one process
// on simulated time, with the world physics, the optics rendering real images, the real
// measurement core (tactile::Extractor) and the real control core (tactile::control) in the
// loop. Deterministic for a seed: no clock is read.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/control/types.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/truth.hpp"
#include "tactile/util/host_load.hpp"
#include "tactile/util/percentile.hpp"

namespace tactile::rig {

struct SlipMetrics {
  std::string detector = "paper";  // control::to_string(SlipDetectorKind)
  double precision = 0;
  double recall = 0;
  double latency_frames_p50 = 0;
  double latency_frames_p99 = 0;
  std::uint64_t true_positives = 0;
  std::uint64_t false_positives = 0;
  std::uint64_t false_negatives = 0;
  std::uint64_t onsets = 0;         // true slip episodes that began
  std::uint64_t missed_onsets = 0;  // of which no SLIP ever covered (counted as kMissedLatency)
  // The same element-frame score for an ideal sensor: the paper's test (centroid change above the
  // threshold) on the true shear displacement of each visible element, without noise or
  // centroiding error. What the detection principle itself reaches against this truth.
  double ideal_precision = 0;
  double ideal_recall = 0;
  // The same scores without the element-frames at the truth's three edges, where the label
  // itself is undecided: within one frame of a visibility change, a load ratio of 0.07-0.13,
  // or a motion (the larger of the tip's slip and the surface's motion) of 0.67-1.5 times the
  // threshold.
  double precision_clear = 0;
  double recall_clear = 0;
  double ideal_precision_clear = 0;
  double ideal_recall_clear = 0;
  std::uint64_t edge_frames = 0;  // element-frames at an edge, truly sliding or not
  // The incipient lead (IncipientLead, scoring.hpp): the median over the gross-slip onsets that
  // the truth shows partial slip before (0 when there are none), their count, and how many of
  // them the detector flagged before the onset (lead > 0).
  double incipient_lead_frames = 0;
  std::uint64_t incipient_episodes = 0;
  std::uint64_t incipient_detected = 0;
};

// Latency given to an onset that no SLIP covered within its episode and two frames after.
inline constexpr double kMissedLatencyFrames = 1000.0;

// The q-quantile of `v` by nearest rank (util/percentile.hpp), 0 when empty: every percentile of
// the report (slip latency in frames, and latency_ms of a real-time run).
using util::nearest_rank_percentile;

// The element-frame slip score of a run against its truth (SlipMetrics), the same for the
// lockstep and the real-time runs: the measurement's test, the onsets and their latency, and the
// ideal sensor beside it.
class SlipScorer {
 public:
  // One element of one fingertip in frame `frame` (frames counted from the start): `predicted`
  // is the detector's decision on the measured frame, `ideal` its decision on the truth's own
  // readings (an ideal sensor), `threshold_mm` the slip threshold of the moment.
  void add(std::size_t fingertip, std::size_t element, std::uint64_t frame, bool predicted,
           bool ideal, const ElementTruth& truth, double threshold_mm);
  // Closes the onsets still waiting (never covered) and fills the metrics. Call once, at the end.
  void finish(SlipMetrics& out);

 private:
  struct Element {
    bool was_sliding = false;
    bool pending = false;  // an onset not covered yet
    std::uint64_t onset = 0;
    std::uint64_t last_true = 0;
    bool was_visible = false;
    bool visibility_changed = false;  // in the last frame
  };
  struct Counts {
    std::uint64_t tp = 0, fp = 0, fn = 0;
    void add(bool predicted, bool truth) {
      tp += predicted && truth ? 1 : 0;
      fp += predicted && !truth ? 1 : 0;
      fn += !predicted && truth ? 1 : 0;
    }
  };
  std::array<std::array<Element, kElementsPerFingertip>, kFingertips> elements_{};
  std::vector<double> latencies_;
  SlipMetrics m_;
  Counts measured_, ideal_, clear_, ideal_clear_;
};

// The grip against the least that holds (docs/rig.md, "The grip's truth"), over the frames the
// cap is held by the fingers (GripTruth::held): the ratio of the grip applied (the smaller
// fingertip's total normal force) to the least steady grip (the largest least grip within
// kSteadyGripHalfWindowS), and to the instant's least grip. Nearest-rank percentiles; the
// ratios are meaningless (written null) without a held frame.
struct GripMetrics {
  std::uint64_t held_frames = 0;
  double ratio_p50 = 0;
  double ratio_p95 = 0;
  double ratio_max = 0;
  double instant_ratio_p50 = 0;
  double instant_ratio_p95 = 0;
  double applied_p50_N = 0;       // the grip applied, per fingertip
  double steady_need_max_N = 0;   // the largest least steady grip
  double cap_slide_carry_mm = 0;  // the cap's slide in the fingers while held, summed
};

// The Phases, for counts per phase.
inline constexpr std::size_t kPhaseCount = static_cast<std::size_t>(control::Phase::kAborted) + 1;

// The scenario report: the fixed keys plus a few of our own (docs/rig.md).
struct Report {
  bool completed = false;
  bool dropped = false;
  std::optional<std::string> grasp_classified;    // "grasp" / "release" on lift, or null
  std::optional<std::string> release_classified;  // "release" on lowering, or null
  int recompressions = 0;
  // The re-compressions by the controller's phase they came in (written by phase name).
  std::array<int, kPhaseCount> recompressions_by_phase{};
  int twist_cycles = 0;
  std::optional<int> tightened_cycle;
  std::optional<int> true_tight_cycle;
  double max_fz_N = 0;
  int over_events = 0;
  SlipMetrics slip;        // the detector the controller ran
  SlipMetrics slip_other;  // the other detector on the same frames (it decided nothing)
  double force_rmse_normal_N = 0;
  double force_rmse_shear_N = 0;
  // Distributed runs only: camera timestamp -> ArmCommand received by the arm controller (ms).
  struct Latency {
    double p50 = 0;
    double p99 = 0;
    double max = 0;
  };
  std::optional<Latency> latency_ms;
  // Distributed runs only: the machine over the run (its CPU steal share, load average and
  // cores), written as `machine` after every other key, with whether it explains the latency.
  std::optional<util::MachineLoad> machine;
  // Tightness timing (docs/rig.md): "tight" declared (the controller's CAP_TIGHT) minus the cap
  // meeting its stop in the truth (the first frame with cap_tight), in seconds, and the wrist's
  // turn in the tightening direction between the two instants (the over-tightening), in degrees.
  // Null when either is missing.
  std::optional<double> tight_time_error_s;
  std::optional<double> tight_error_deg;
  // The sweep's negative cases (docs/slip.md): "normal", "bottle_displaced" (the bottle stands
  // away from the controller's place: no release may be classified, the fingers may not open
  // with the cap in the air) or "cap_held" (the cap is held to the table: no grasp may be
  // classified); whether the run passed it (null for "normal"); and whether the controller
  // commanded OPEN while the cap was in the air (neither on the table nor on the bottle).
  std::string scenario_case = "normal";
  std::optional<bool> negative_case_passed;
  bool opened_in_air = false;
  // Whether the hand can hold this cap within F2 (truth: weight, peak acceleration, mu_s; the
  // largest disturbance).
  HoldNeed hold;
  // The scenario's disturbances as applied, written as `disturbance` when the scenario has one:
  // each set one's magnitude, direction and timing, its start on the run's clock (null: its stage
  // never came). Absent: no key, the report as without disturbances.
  std::optional<DisturbanceParams> disturbance;
  // A fragile object (cap.crush_force_n), written as `fragile`: the crush force, whether the grip
  // broke it and when, the largest grip applied. A broken object is said here alone:
  // `completed` and `negative_case_passed` stay the controller's decisions. Absent: no key.
  std::optional<CrushTruth> fragile;
  GripMetrics grip;
  // A lab's sensor (the scenario's sensor.calibration), written as `sensor`: the file and the
  // image it gave the cameras. Absent: no key, the rig's own sensor.
  std::optional<LabSensor> sensor;
  // The controller the run scored: its slip detector and its grip (control::to_string of the
  // scenario's controller configuration), written as `controller`, before `grip` and
  // `recompressions_by_stage`.
  struct Controller {
    std::string slip_detector = "paper";
    std::string grip = "paper";
  };
  Controller controller;
  // Ours.
  std::uint64_t seed = 0;
  double sim_time_s = 0;
  std::uint64_t frames = 0;
  double physics_step_s = 0;
  double final_cap_angle_deg = 0;
  std::string end_reason;  // "done", "aborted: ...", "max_time", "physics"
  double normal_full_scale_N = 0;
};

// One camera frame of the run, for plots.
struct FrameSample {
  std::uint64_t frame = 0;  // counted from the start of the run
  double t = 0;
  std::uint8_t phase = 0;  // control::Phase
  std::uint32_t twist_cycle = 0;
  std::array<bool, kFingertips> touch{}, slip{}, over{}, true_slip{};
  std::array<double, kFingertips> max_fz_measured{}, max_fz_true{};
  // Apex position along the transport (the horizontal direction from cap to bottle), m: the
  // paper's x-directional fingertip position.
  std::array<double, kFingertips> fingertip_x_m{};
  // Signed y-directional centroid change (mm) of the in-contact element moving most.
  std::array<double, kFingertips> dy_mm{};
  double cap_angle_deg = 0;
  double cap_z_m = 0;
  double cap_yaw_rad = 0;
  std::uint8_t cap_place = 0;  // CapPlace
  double wrist_z_m = 0;
  double wrist_yaw_rad = 0;
  // Element-frames of this frame scored as true positive, false positive, false negative.
  std::array<std::uint16_t, kFingertips> tp{}, fp{}, fn{};
  // The grip's truth (GripTruth): the least grip that holds the cap now, the grip applied (the
  // smaller fingertip's total normal force), and whether the fingers alone hold the cap.
  double grip_need_n = 0;
  double grip_applied_n = 0;
  bool grip_held = false;
};

struct EventRecord {
  double t = 0;
  std::uint8_t kind = 0;  // control::EventKind
  std::string kind_name;
  std::string phase;
  std::uint32_t cycle = 0;
  int fingertip = -1;
  double value = 0;
  std::string text;
};

// The measured and true state of both fingertips' elements at one moment (Fig. 3 style plots).
struct Snapshot {
  double t = 0;
  std::string label;
  struct Element {
    double x_px = 0, y_px = 0;  // disk centre
    bool contact = false;       // measured
    bool slip = false;          // measured per-frame displacement beyond the threshold
    bool true_sliding = false;
    double ux_mm = 0, uy_mm = 0;  // measured shear displacement
    double dx_mm = 0, dy_mm = 0;  // measured per-frame displacement
    double fz_n = 0;
  };
  std::array<std::array<Element, kElementsPerFingertip>, kFingertips> fingertips{};
};

// An element-frame where the measurement and the truth disagree about slip (for diagnosis).
struct Mismatch {
  double t = 0;
  int fingertip = 0;
  std::uint32_t element = 0;
  bool measured_slip = false;
  double measured_d_mm = 0;  // |(dx, dy)| measured
  double measured_fz = 0;
  std::uint8_t reasons = 0;  // the run's detector's control::kSlip* bits
  ElementTruth truth;
};

struct RunSeries {
  std::vector<FrameSample> frames;
  std::vector<Mismatch> mismatches;
  std::vector<EventRecord> events;
  std::vector<Snapshot> snapshots;
};

// The learned slip detector's training rows of one run (slip_train, docs/slip.md): each
// element-frame of the measured frames that has the detector's signals, with the truth's label
// and a weight. Element-frames no signal marks (every length and load below half its threshold,
// no slip in the truth, none decided) are kept one in kSlipFeatureEasyStride, with that weight.
inline constexpr std::uint32_t kSlipFeatureEasyStride = 8;
struct SlipFeatureLog {
  std::vector<control::SlipFeatures> x;
  std::vector<std::uint8_t> label;
  std::vector<float> weight;
};

struct LockstepOptions {
  // Physics step override (0: the scenario's); the step-size test runs with a tenth.
  double dt_s = 0;
  bool record_series = true;
  // Collects the learned detector's training rows when set.
  SlipFeatureLog* slip_features = nullptr;
};

struct LockstepResult {
  Report report;
  RunSeries series;
  std::array<Calibration, kFingertips> calibrations;
  bool physics_finite = true;  // no step ever produced a non-finite value
};

// Runs the scenario to its end (DONE, ABORTED, a drop or max_time_s). Throws only for a bad
// scenario (std::invalid_argument from the cores' constructors).
LockstepResult run_lockstep(const Scenario& scenario, const LockstepOptions& options = {});

// The per-frame series as CSV (one header line, one line per frame).
std::string series_csv(const RunSeries& series);

// The mismatches as CSV.
std::string mismatches_csv(const RunSeries& series);

// The report as one JSON object (the fixed keys first; latency_ms is null in
// lockstep). Deterministic text: the same report gives the same bytes.
std::string report_json(const Report& report);

}  // namespace tactile::rig
