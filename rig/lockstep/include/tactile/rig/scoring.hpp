#pragma once

// The one scorer of a rig run (docs/rig.md, "Lockstep runner and report"; architecture.md,
// rule 9): it scores the measured frames against the truth of the same instant, element-frame by
// element-frame, tallies the controller's events into the report and records the series. The
// lockstep runner feeds it frame by frame; the real-time rig feeds it the truth when it renders
// and the measured frames and events as they arrive over the wire, later and interleaved. Both
// get the same metrics for the same stream (ScoringTest). No clock: times are arguments.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "tactile/control/config.hpp"
#include "tactile/control/flag_analyzer.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/control/types.hpp"
#include "tactile/reading.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/truth.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {

// The measurement's slip threshold while the controller is in `phase`: dr, or dr times the
// twist factor in Phase II (the control core's own FlagAnalyzer::dr).
double slip_threshold_mm(const control::Config& cfg, control::Phase phase);

// Where the hand is at a frame's instant, for the series: the paper's Fig. 10 x (the apex's
// position along the transport) and the wrist.
struct FramePose {
  std::array<double, kFingertips> fingertip_x_m{};
  double wrist_z_m = 0;
  double wrist_yaw_rad = 0;
};

// The transport's direction: horizontal, from the cap's place to the bottle.
Vec3 transport_direction(const WorldParams& world);
// The world's pose at this instant, with x measured along `transport` (transport_direction).
FramePose frame_pose(const World& world, Vec3 transport);

// What the controller had decided when a frame was taken.
struct ControllerState {
  control::Phase phase = control::Phase::kIdle;
  std::uint32_t twist_cycle = 0;
};

// The incipient lead (docs/slip.md, "The incipient lead"), per fingertip. By the truth, a frame
// is gross slip when more than half of the fingertip's in-contact elements slide, partial slip
// when some slide but not that many. A gross-slip onset that follows partial-slip frames (its
// run-up) is an episode; the detector's lead is the frames from the first frame of the run-up in
// which it decided any element of that fingertip slipping (incipient or slip) to the onset, 0
// when it decided none before the onset. An onset straight from stick has no run-up: no episode.
class IncipientLead {
 public:
  // One frame of one fingertip (frames in order per fingertip) with each detector's decision on
  // it: [0] the run's, [1] the other.
  void add(std::size_t fingertip, std::uint64_t frame, const FingertipTruth& truth,
           const std::array<const control::FingertipSlip*, 2>& decided, std::size_t elements);
  // Detector d's median lead, episodes and detected episodes into `m`.
  void finish(std::size_t d, SlipMetrics& m) const;

 private:
  struct Tip {
    bool in_run_up = false;
    std::array<std::optional<std::uint64_t>, 2> first_flag{};  // per detector, in the run-up
  };
  std::array<Tip, kFingertips> tips_{};
  std::array<std::vector<double>, 2> leads_{};
};

// The least steady grip (docs/rig.md, "The grip's truth"): no grip follows the arm's vibration
// frame by frame, so a frame's least steady grip is the largest least grip of the frames within
// this much before and after it (a centred 0.2 s window, cut at the run's ends).
inline constexpr double kSteadyGripHalfWindowS = 0.1;

// Into `steady[k]`: the largest `need[j]` with |t[j] - t[k]| <= half_window_s; `t` ascending,
// all three the same size. Allocates nothing.
void steady_need(std::span<const double> t, std::span<const double> need, double half_window_s,
                 std::span<double> steady);

// The report's `grip` (GripMetrics) from the grip's truth of each rendered frame, in order.
class GripScorer {
 public:
  // Room for this many frames: add() allocates nothing up to it.
  void reserve(std::size_t frames);
  void add(double t, const GripTruth& grip);
  GripMetrics finish();

 private:
  std::vector<double> t_, need_, applied_;
  std::vector<std::uint8_t> held_;
  double slide_mm_ = 0;
};

class RunScorer {
 public:
  // Fills `run.report` and (with `record_series`) `run.series`; `run.calibrations` must be set.
  RunScorer(LockstepResult& run, const control::Config& cfg, bool record_series);
  // Room for this many frames in the per-frame records (the grip's truth).
  void reserve(std::size_t frames) { grip_.reserve(frames); }

  // The truth of one rendered frame (`frame` counted from the start), the controller's state
  // then and the hand's pose: a series sample, the cap and tightening facts.
  void add_truth(std::uint64_t frame, double t, const GroundTruth& truth,
                 const ControllerState& controller, const FramePose& pose);
  // The grip's truth of the same frame, at `t` (the report's `grip`, and `fragile`).
  void add_grip(double t, const GripTruth& grip);
  // The object breaks under a grip above `crush_force_n` (cap.crush_force_n; 0: not fragile,
  // the report has no `fragile`).
  void score_crush(double crush_force_n) { crush_.crush_force_n = crush_force_n; }
  // One measured frame of one fingertip with the truth of the same frame (add_truth first).
  // `phase` is the controller's phase the frame was taken in: it sets the slip threshold; `arm`
  // the arm's motion the controller saw with it (control::ArmMotionEstimator on the reported
  // wrist pose). Both slip detectors decide on it, and on the truth's own readings (the ideal
  // sensor); the configured one is the run's `slip`, the other `slip_other`.
  void add_measurement(std::size_t fingertip, std::uint64_t frame,
                       std::span<const ElementReading> measured, const FingertipTruth& truth,
                       control::Phase phase, const control::ArmMotion& arm);
  void add_event(const control::Event& event, double t);
  // From now on, the learned detector's signals of every measured frame with the truth's labels
  // go to `log` (training, slip_train).
  void log_features(SlipFeatureLog* log);
  // Closes the metrics.
  void finish(bool dropped, double sim_time_s, std::uint64_t frames);

 private:
  FrameSample* sample_for(std::uint64_t frame);
  void snapshot(double t, const char* label);

  LockstepResult& run_;
  control::Config cfg_;
  control::FlagAnalyzer flags_;
  // The wrist's turn in the tightening direction (+1: yaw increasing tightens), summed over the
  // frames' increments in that direction only (the return strokes with open fingers do not
  // count), and its value when the cap met its stop and when "tight" was declared.
  double tighten_yaw_sign_ = -1;
  bool have_wrist_yaw_ = false;
  double last_wrist_yaw_rad_ = 0;
  double wrist_turn_deg_ = 0;
  struct Moment {
    double t = 0;
    double wrist_turn_deg = 0;
  };
  std::optional<Moment> cap_stop_;
  std::optional<Moment> declared_tight_;
  bool record_;
  // [0]: the run's detector (the controller's), [1]: the other; each on the measured frames and
  // on the ideal sensor's readings.
  std::array<control::SlipDetector, 2> measured_;
  std::array<control::SlipDetector, 2> ideal_;
  std::array<SlipScorer, 2> slip_;
  // The training rows: a learned detector on the measured frames, fed as the run's detector is.
  SlipFeatureLog* feature_log_ = nullptr;
  std::optional<control::SlipDetector> recorder_;
  std::uint32_t easy_seen_ = 0;
  IncipientLead lead_;
  GripScorer grip_;
  CrushTruth crush_;
  // The ideal sensor's readings: the truth's forces and per-frame shear displacement.
  struct IdealTip {
    std::array<ElementReading, kElementsPerFingertip> readings{};
    std::array<bool, kElementsPerFingertip> was_visible{};
    std::array<double, kElementsPerFingertip> ux_mm{}, uy_mm{};
  };
  std::array<IdealTip, kFingertips> ideal_tips_{};
  // Per fingertip, summed in fingertip order at the end: the real-time rig gets the two
  // fingertips' frames in either order, and a sum's rounding must not depend on it.
  std::array<double, kFingertips> sq_normal_{};
  std::array<double, kFingertips> sq_shear_{};
  std::uint64_t n_normal_ = 0;
  std::uint64_t n_shear_ = 0;
  bool transport_snapshot_ = false;
  // The latest measured frame of each fingertip, for the snapshots at events.
  struct Latest {
    std::array<ElementReading, kElementsPerFingertip> readings{};
    std::array<bool, kElementsPerFingertip> true_sliding{};
    std::array<bool, kElementsPerFingertip> slip{};  // the run's detector
  };
  std::array<Latest, kFingertips> latest_{};
};

}  // namespace tactile::rig
