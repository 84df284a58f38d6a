#pragma once

// The control core's inputs and outputs (docs/control.md). Plain fixed-size data: an update
// reads these and writes these without allocating.
//
// Frames. World: z up, origin on the table top. Wrist frame: x_w is the closing axis,
// fingertip 0 ("left") at -x_w squeezes toward +x_w, fingertip 1 ("right") at +x_w squeezes
// toward -x_w, z_w up. Fingertip frame: z_f is the squeeze direction, y_f points down (-z_w),
// x_f = y_f x z_f. A reading's dx_mm/dy_mm lie along x_f/y_f (image columns/rows).
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "tactile/control/config.hpp"
#include "tactile/geometry.hpp"
#include "tactile/reading.hpp"

namespace tactile::control {

inline constexpr std::size_t kFingertips = 2;

// Position (m) of the grasp centre, midway between the fingertips, and yaw (rad) about world z.
struct WristPose {
  Vec3 position_m;
  double yaw_rad = 0;
};

// The latest tactile frame of one fingertip, as the caller (hand_node) holds it.
struct FingertipInput {
  // Every calibrated element in calibration order.
  std::span<const ElementReading> elements;
  // Unit inward normal of each element in the fingertip frame, same order as `elements`
  // (calibration `normal`). A missing, non-finite or zero normal counts as (0, 0, 1).
  std::span<const Vec3> normals;
  std::uint64_t sequence = 0;
  std::int64_t camera_timestamp_ns = 0;
  // A new whole frame arrived since the previous update: only such frames can raise SLIP.
  bool fresh = false;
  // Decided by the caller (e.g. no frame for Config::stale_after_s): the controller holds.
  bool stale = false;
};

struct ArmFeedback {
  WristPose wrist;
  std::uint32_t active_segment_id = 0;
  bool segment_done = false;
  bool holding = false;
  // The arm controller holds the arm because it heard nothing from us within its deadman (not
  // a hold we asked for); set until we command again.
  bool deadman = false;
  std::array<Vec3, kFingertips> fingertip_position_m{};  // wrist frame
};

struct ControllerInput {
  std::array<FingertipInput, kFingertips> fingertips;
  ArmFeedback arm;
  double now_s = 0;  // the caller's clock; the controller reads no clock of its own
};

// ---------------------------------------------------------------------------------------------
// Commands: a mirror of the wire's ArmCommand oneof.

enum class CommandKind : std::uint8_t { kNone, kMoveTo, kFingerVelocities, kHold, kOpen, kStop };
const char* to_string(CommandKind k);

// A trajectory segment. `name` points to a string literal ("MOVE3"): no allocation.
struct MoveTo {
  std::uint32_t segment_id = 0;
  const char* name = "";
  WristPose target;
  double max_speed_mps = 0;
  double max_yaw_rate_rps = 0;
  bool keep_finger_velocities = false;
};

// Each fingertip's velocity in its own fingertip frame; persists on the arm until changed.
struct FingerVelocities {
  std::array<Vec3, kFingertips> velocity_mps{};
};

// Move both fingertips away along -z_f by distance_m at speed_mps.
struct Open {
  double speed_mps = 0;
  double distance_m = 0;
};

// One command; only the member named by `kind` is meaningful. kNone: nothing new to send.
// Hold and Stop carry no data.
struct Command {
  CommandKind kind = CommandKind::kNone;
  MoveTo move_to;
  FingerVelocities finger_velocities;
  Open open;

  static Command none() { return {}; }
  static Command hold() { return {CommandKind::kHold, {}, {}, {}}; }
  static Command stop() { return {CommandKind::kStop, {}, {}, {}}; }
  static Command move(const MoveTo& m) { return {CommandKind::kMoveTo, m, {}, {}}; }
  static Command velocities(const FingerVelocities& v) {
    return {CommandKind::kFingerVelocities, {}, v, {}};
  }
  static Command open_fingers(const Open& o) { return {CommandKind::kOpen, {}, {}, o}; }
};

// ---------------------------------------------------------------------------------------------
// Steps of the two sequencers.

enum class Phase : std::uint8_t {
  kIdle,
  // Phase I, grasp-move-release (paper Fig. 7)
  kApproach,   // MOVE1: above the cap at the safe height
  kDescend,    // MOVE2: down to the grasp height
  kGrasp,      // SEARCH until TOUCH on both fingertips, settle, "grasping ended"
  kLift,       // MOVE3: up to the carry height, slip direction analysis
  kTransport,  // MOVE4: to above the bottle, re-compression on slip
  kLower,      // MOVE5: down toward a place of unknown height until a negative slip
  kRelease,    // hold, open gently
  kRetract,    // MOVE6: up, clear of the cap
  // Phase II, grasp-twist (paper Fig. 8)
  kTwistApproach,  // back to the reference pose (where the cap was released)
  kTwistGrasp,     // SEARCH until TOUCH on both fingertips, settle
  kTwistTurn,      // turn the wrist by the twist angle, counting slips
  kTwistRelease,   // open
  kTwistReturn,    // turn back with the fingers open
  kTwistFinish,    // cap tight (or cycle cap reached): hold, open, move clear
  // Terminal
  kDone,
  kAborted,
};
const char* to_string(Phase p);
bool is_twist_phase(Phase p);

// How the fingers are driven (the paper's SEARCH and MOVE modes; kOff: not driven).
enum class FingerMode : std::uint8_t { kOff, kSearch, kMove };
const char* to_string(FingerMode m);

// ---------------------------------------------------------------------------------------------
// Events: a mirror of the wire's EventKind.

enum class EventKind : std::uint8_t {
  kPhase = 1,
  kTouch = 2,
  kGraspingEnded = 3,
  kGraspClassified = 4,
  kReleaseClassified = 5,
  kRecompress = 6,
  kOver = 7,
  kTwistCycle = 8,
  kCapTight = 9,
  kStaleHold = 10,
  kResumed = 11,
  kDone = 12,
  kAborted = 13,
};
const char* to_string(EventKind k);

inline constexpr std::int8_t kNoFingertip = -1;

struct Event {
  EventKind kind = EventKind::kPhase;
  Phase phase = Phase::kIdle;  // the step when it happened
  std::uint32_t cycle = 0;     // twist cycle from 1, 0 outside Phase II
  std::int8_t fingertip = kNoFingertip;
  bool has_element = false;
  std::uint32_t element_id = 0;
  double value = 0;       // meaning per kind: docs/control.md
  const char* text = "";  // a string literal
};

// The events of one update, in the order they happened. Fixed capacity: a push beyond it is
// counted in dropped() instead of allocating (the controller never comes near it).
class EventList {
 public:
  static constexpr std::size_t kCapacity = 16;

  bool push(const Event& e) noexcept {
    if (size_ == kCapacity) {
      ++dropped_;
      return false;
    }
    events_[size_++] = e;
    return true;
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t dropped() const { return dropped_; }
  const Event& operator[](std::size_t i) const { return events_[i]; }
  const Event* begin() const { return events_.data(); }
  const Event* end() const { return events_.data() + size_; }
  void clear() noexcept {
    size_ = 0;
    dropped_ = 0;
  }

 private:
  std::array<Event, kCapacity> events_{};
  std::size_t size_ = 0;
  std::size_t dropped_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Flags (paper Fig. 5).

inline constexpr std::int32_t kNoElement = -1;

// Elements of one fingertip the slip detectors decide, and whose ids FingertipFlags names: the
// sensor has 41; elements beyond this are ignored.
inline constexpr std::size_t kMaxSlipElements = 64;

// What the flag analyzer found on one fingertip. Element indices are positions in
// FingertipInput::elements (kNoElement when there is none).
struct FingertipFlags {
  // Some F_z > F1, or SLIP; with the margin grip also a total F_z > grip_touch_n.
  bool touch = false;
  bool slip = false;  // a fresh frame with an in-contact element moving more than dr
  bool over = false;  // some F_z > F2
  std::int32_t max_fz_index = kNoElement;  // largest F_z among in-contact elements
  double max_fz_n = 0;
  std::int32_t slip_max_fz_index = kNoElement;  // largest F_z among the slipping elements
  std::uint32_t slipping_elements = 0;
  // The ids (ElementReading::id) of the slipping elements in input order: the first
  // min(slipping_elements, kMaxSlipElements) are set. What the viewers draw as slipping.
  std::array<std::uint32_t, kMaxSlipElements> slipping_ids{};
  double max_slip_mm = 0;  // largest per-frame displacement magnitude among in-contact elements
  double total_fz_n = 0;   // the sum of the in-contact elements' F_z: the fingertip's grip
  // The elements total_fz_n sums: the grip's stiffness is theirs (the margin grip's servo gain).
  std::uint32_t contact_elements = 0;
};

struct Flags {
  bool search = false;  // fingers in SEARCH mode
  bool move = false;    // fingers in MOVE mode
  bool touch = false;   // some fingertip touches
  bool slip = false;    // some fingertip slips
  bool over = false;    // some fingertip is over F2
  std::array<FingertipFlags, kFingertips> fingertip{};
};

struct ControllerOutput {
  Command command;
  EventList events;
  Flags flags;
  SlipDetectorKind slip_detector = SlipDetectorKind::kPaper;  // the detector that decided SLIP
  Phase phase = Phase::kIdle;
  std::uint32_t twist_cycle = 0;  // 0 before Phase II, then the current cycle from 1
};

}  // namespace tactile::control
