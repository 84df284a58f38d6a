#pragma once

// Slip detection per element and per fingertip, behind one interface (docs/slip.md, "The
// detectors"): the paper's rule and the field detector.
//
// paper: an in-contact element of a fresh frame slips when its centroid moved more than dr in
//   the frame (the paper's section IV; stateless).
// field: each element's displacement against the rigid motion (translation and rotation) fitted
//   to the contact's elements, its friction-cone load |F_t| / F_n against a friction coefficient
//   estimated online from the loads it has seen break away, and the arm's reported motion that
//   the contact's shear does not follow. Per element a state (stick, incipient, slip) with a
//   slip velocity. No friction coefficient is configured.
// learned: the field detector's signals (SlipSignal, slip_signals.hpp) for each element through a
//   small boosted-tree model (ObliviousForest) compiled in (slip_model.inc, and
//   slip_model_margin.inc for the margin grip; written by slip_train from sweeps of seeds other
//   than the benchmark's): an element slips when the model's score
//   exceeds its decision level. The history, the friction estimate and the states' gross/incipient
//   split stay the field detector's, so the signals do not depend on the model.
//
// Pure and allocation-free; every output is finite whatever the input (NaN readings count as no
// contact). Elements beyond kMaxSlipElements of one fingertip are ignored (the sensor has 41).
#include <array>
#include <cstddef>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/oblivious_forest.hpp"
#include "tactile/control/slip_signals.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

enum class ElementSlipState : std::uint8_t {
  kNone,       // not in contact, or no displacement measured
  kStick,      // in contact, not slipping
  kIncipient,  // slipping while the contact as a whole sticks (partial slip)
  kSlip,       // slipping with the contact moving as a whole (gross slip)
};
const char* to_string(ElementSlipState s);
inline bool slipping(ElementSlipState s) {
  return s == ElementSlipState::kIncipient || s == ElementSlipState::kSlip;
}

// The arm's reported motion at this frame (the wrist's speed and yaw rate), from the ArmState
// feedback: the motion the contact's shear should follow when the cap is held.
struct ArmMotion {
  double speed_mps = 0;
  double yaw_rate_rps = 0;
};

// The arm's motion from successive reported wrist poses and the caller's clock: the controller
// feeds it ArmFeedback::wrist, the rig the same pose. A first pose, a time that does not advance
// or a non-finite value gives no motion.
class ArmMotionEstimator {
 public:
  ArmMotion update(const WristPose& wrist, double now_s) noexcept;
  void reset() noexcept { has_last_ = false; }

 private:
  bool has_last_ = false;
  WristPose last_;
  double last_s_ = 0;
  ArmMotion motion_;
};

// Why an element was decided slipping (bits of FingertipSlip::reasons): its own motion beyond dr
// under load (the paper's test, with the field detector's load gate), its departure from the
// contact's rigid motion, a breakaway (the load ratio fell from the cone's edge), or a slip that
// goes on at the cone's edge while the contact or the arm moves.
inline constexpr std::uint8_t kSlipMoved = 1;
inline constexpr std::uint8_t kSlipLeftRigid = 2;
inline constexpr std::uint8_t kSlipBrokeAway = 4;
inline constexpr std::uint8_t kSlipDragged = 8;
// The learned detector decided slip where none of the field detector's rules did.
inline constexpr std::uint8_t kSlipLearned = 16;

// One fingertip's decisions on its latest fresh frame.
struct FingertipSlip {
  std::array<ElementSlipState, kMaxSlipElements> state{};
  // Estimated slip of each slipping element over the frame (mm per frame), 0 otherwise.
  std::array<double, kMaxSlipElements> slip_mm{};
  std::array<std::uint8_t, kMaxSlipElements> reasons{};  // kSlip* bits, 0 when not slipping
  std::uint32_t incipient = 0;                           // elements in kIncipient
  std::uint32_t slipping = 0;                            // elements in kIncipient or kSlip
  ElementSlipState fingertip = ElementSlipState::kNone;  // the worst element's state
  // The contact's fitted rigid motion over the frame (mm per frame) at its centroid.
  double rigid_mm = 0;
  // The friction coefficient estimated so far (field; 0 for paper).
  double mu_estimate = 0;
};

// What the field detector keeps of an element's last fresh frames.
struct ElementHistory {
  bool valid = false;
  bool sliding = false;  // the field rules' decision
  double ratio = 0;      // |F_t| / F_n
  // For the learned detector's signals: the last frame's F_n, its change, and the motion and
  // departure (in dr) of the last two frames.
  double fz = 0;
  double dfz = 0;
  double moved = 0;
  double moved2 = 0;
  double departed = 0;
};

// The field rules' thresholds (Config's field_* settings, docs/slip.md).
struct FieldParams {
  double partial_slip_ratio = 0;  // rho: a load ratio of rho * mu or more is loaded
  double edge_ratio = 0;          // at the cone's edge from edge * mu
  double drop_ratio = 0;          // a breakaway: the ratio fell from the edge by drop * mu
  double min_fz_n = 0;            // F_n below which no load ratio is formed
  double arm_speed_mps = 0;       // the arm moves above this speed
  double arm_yaw_rate_rps = 0;    // or this yaw rate
};

// The paper's test on one reading: in contact, displacement measured, |(dx, dy)| > threshold.
bool paper_slip(const ElementReading& r, double threshold_mm) noexcept;

class SlipDetector {
 public:
  // The kind and the field detector's parameters come from `cfg` (validated by the caller).
  SlipDetector(SlipDetectorKind kind, const Config& cfg);
  explicit SlipDetector(const Config& cfg) : SlipDetector(cfg.slip_detector, cfg) {}

  SlipDetectorKind kind() const { return kind_; }
  // Forgets the elements' history and the friction estimate (a new task).
  void reset() noexcept;

  // One fingertip's frame. Only a fresh frame is decided and updates the history; otherwise the
  // result is "nothing slips" with the history kept. `threshold_mm`: dr, or dr times the twist
  // factor in Phase II (FlagAnalyzer::dr).
  const FingertipSlip& update(std::size_t fingertip, const FingertipInput& in, double threshold_mm,
                              const ArmMotion& arm) noexcept;
  const FingertipSlip& last(std::size_t fingertip) const { return out_[fingertip]; }
  // Which elements of the latest fresh frame of `fingertip` have the learned detector's signals
  // (kind learned only; otherwise none has), and one element's signals (all 0 where it has none).
  const std::array<bool, kMaxSlipElements>& has_features(std::size_t fingertip) const {
    return has_features_[fingertip];
  }
  SlipFeatures features(std::size_t fingertip, std::size_t element) const noexcept;
  // The compiled-in model for a grip (slip_model.inc for the paper's, slip_model_margin.inc for
  // the margin grip's light contacts; no trees: learned decides as field) and its decision
  // level: the learned detector decides slip when the model's score exceeds it. A detector uses
  // its Config::grip's.
  static const ObliviousForest& model(GripKind grip = GripKind::kPaper) noexcept;
  static double model_decision(GripKind grip = GripKind::kPaper) noexcept;

 private:
  void decide_paper(const FingertipInput& in, double threshold_mm, FingertipSlip& out) noexcept;
  // The field rules decide each element; the learned detector's signals are written beside them
  // (kind learned), then decide_learned.
  void decide_field(std::size_t f, const FingertipInput& in, double threshold_mm,
                    const ArmMotion& arm, FingertipSlip& out) noexcept;
  // The model decides the elements that have signals (the first `count` of the frame);
  // `contact_moves`: the contact's rigid translation exceeds the threshold.
  void decide_learned(std::size_t f, std::size_t count, double threshold_mm, bool contact_moves,
                      FingertipSlip& out) noexcept;
  // The frame period from the camera's timestamps (0 until two frames came 0-1 s apart).
  double frame_period_s(std::size_t f, std::int64_t camera_timestamp_ns) noexcept;

  SlipDetectorKind kind_;
  GripKind grip_;  // the model's
  FieldParams field_;
  double mu_initial_;
  std::array<std::array<ElementHistory, kMaxSlipElements>, kFingertips> history_{};
  // Per fingertip: each estimate depends only on its own fingertip's frames, so the order in which
  // a caller feeds the two fingertips of one instant changes nothing.
  std::array<double, kFingertips> mu_{};
  std::array<FingertipSlip, kFingertips> out_{};
  // The learned detector's per-fingertip signals of the last fresh frame: the sum of F_n, the
  // camera timestamp and frame period, the share of the contact the field detector decided
  // slipping.
  std::array<double, kFingertips> total_fz_{};
  std::array<std::int64_t, kFingertips> last_ts_ns_{};
  std::array<double, kFingertips> period_s_{};
  std::array<double, kFingertips> share_slipping_{};
  // The learned detector's signals of each fingertip's last fresh frame, by column: the elements
  // that have them in order (column_of_), and their scores (scratch of one frame).
  std::array<SlipColumns, kFingertips> columns_{};
  std::array<std::array<std::uint8_t, kMaxSlipElements>, kFingertips> column_of_{};
  std::array<std::array<bool, kMaxSlipElements>, kFingertips> has_features_{};
  std::array<float, kMaxSlipElements> score_{};
};

}  // namespace tactile::control
