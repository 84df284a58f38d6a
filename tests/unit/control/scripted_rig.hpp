#pragma once

// A scripted stand-in for the arm, the two fingertips and the cap, for sequence tests of the
// control core. It carries out commands the way the real rig does (segments in straight lines at
// bounded speed, finger velocities that persist, Hold, Open, Stop) and turns each fingertip's
// indentation into normal forces on five elements. Slips are not simulated: a test's script
// injects them, keyed on what the rig is doing (the segment running, frames since it started),
// which is how the paper's experiment is replayed: weight on lift, vibration in transport, the
// bottle on lowering, a cap that tightens.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tactile/control/controller.hpp"

namespace tactile::control::testing {

inline constexpr std::size_t kElements = 5;

// The scripts replay the paper's experiment for the paper's slip rule: an injected slip is one
// element's motion beyond dr, which is all that rule reads (the field and learned detectors, the
// default, read the whole contact's motion and load: slip_detector_test.cpp).
inline Config paper_config() {
  Config c;
  c.slip_detector = SlipDetectorKind::kPaper;
  return c;
}

// The test fingertip: element 0 at the dome's pole, 1 above it (toward -y_f, up), 2 below it
// (toward +y_f, down), 3 toward -x_f, 4 toward +x_f, each 30 degrees off the pole. The normal is
// the inward normal at the element: where pushing presses it harder.
inline std::array<Vec3, kElements> dome_normals() {
  const double s = 0.5;
  const double c = std::sqrt(3.0) / 2.0;
  return {{{0, 0, 1}, {0, -s, c}, {0, s, c}, {-s, 0, c}, {s, 0, c}}};
}

// Share of the pole's normal force that each element carries.
inline constexpr std::array<double, kElements> kShare{1.0, 0.3, 0.35, 0.25, 0.25};

class ScriptedRig {
 public:
  struct Options {
    double dt_s = 0.01;                // one camera frame of both fingertips per update
    double stiffness_n_per_mm = 3.0;   // pole force per mm of indentation
    double initial_gap_mm = 2.0;       // fingertip to cap before the first search
    double fingertip_lever_m = 0.015;  // each fingertip's distance from the wrist's axis
    WristPose start{{0.35, -0.10, 0.25}, 0.0};
  };
  using Script = std::function<void(ScriptedRig&)>;

  ScriptedRig(Options o, Script script) : o_(o), script_(std::move(script)), wrist_(o.start) {
    gap_mm_.fill(o.initial_gap_mm);
    normals_ = dome_normals();
    for (auto& tip : readings_) {
      for (std::size_t i = 0; i < kElements; ++i)
        tip[i].id = static_cast<std::uint32_t>(10 + i);
    }
  }

  // --- what a script sees and does -----------------------------------------------------------
  double now() const { return now_s_; }
  const WristPose& wrist() const { return wrist_; }
  // The name of the segment last commanded ("" before any), and frames since it was commanded.
  std::string segment() const { return segment_.name; }
  int segment_frames() const { return segment_frames_; }
  bool segment_done() const { return segment_done_; }
  // How many segments of this name were commanded so far (the current one included).
  int segments_named(const std::string& name) const {
    int n = 0;
    for (const auto& s : segment_names_)
      n += s == name ? 1 : 0;
    return n;
  }
  bool wrist_held() const { return wrist_held_; }
  bool stopped() const { return stopped_; }
  double pole_fz(std::size_t tip) const { return pole_force(tip); }
  bool in_contact(std::size_t tip) const { return pole_force(tip) > kContactN; }
  // Displacement of one element in the coming frame (mm per frame, fingertip frame).
  void slip(std::size_t tip, std::size_t element, double dx_mm, double dy_mm) {
    injected_[tip][element] = {dx_mm, dy_mm, 1.0};
  }
  // Shear force along x_f on every in-contact element of both fingertips in the coming frame (N):
  // the twist torque the cap resists the turn with, fx_n * kElements * 2 * fingertip_lever_m in
  // the clockwise direction (docs/slip.md, "Tightness from the twist torque").
  void twist_load(double fx_n) { twist_fx_n_ = fx_n; }
  void set_stale(std::size_t tip, bool stale) { stale_[tip] = stale; }
  // The arm controller's deadman holds the wrist (no command of the controller's), until
  // `deadman_resume`, which stands for hand_node sending the current segment again.
  void deadman_hold() { wrist_held_ = deadman_ = true; }
  void deadman_resume() { wrist_held_ = deadman_ = false; }
  // The next input says `holding` (a feedback that lags a command), the wrist moving on.
  void report_holding_once() { holding_once_ = true; }
  void set_fresh(std::size_t tip, bool fresh) { fresh_[tip] = fresh; }
  const Vec3& finger_velocity(std::size_t tip) const { return finger_velocity_[tip]; }

  // --- the loop ---------------------------------------------------------------------------------
  // Runs the script, then builds this frame's readings and the arm's state.
  ControllerInput next_input() {
    if (script_) script_(*this);
    ControllerInput in;
    for (std::size_t f = 0; f < kFingertips; ++f) {
      const double pole = pole_force(f);
      for (std::size_t i = 0; i < kElements; ++i) {
        ElementReading& r = readings_[f][i];
        const double fz = pole * kShare[i];
        const bool contact = fz > kContactN;
        r.has_displacement = contact && r.contact;
        r.contact = contact;
        r.fz = contact ? fz : 0.0;
        r.G = contact ? 1000.0 * fz : 0.0;
        const bool moved = r.has_displacement && injected_[f][i].z > 0;
        r.dx_mm = moved ? injected_[f][i].x : 0.0;
        r.dy_mm = moved ? injected_[f][i].y : 0.0;
        // A slipping element carries a shear load (half its normal force): what makes a
        // motion a slip for the field detector too.
        r.fy = moved ? 0.5 * r.fz : 0.0;
        r.fx = contact ? twist_fx_n_ : 0.0;
        injected_[f][i] = {};
      }
      FingertipInput& t = in.fingertips[f];
      t.elements = readings_[f];
      t.normals = normals_;
      t.sequence = ++sequence_[f];
      t.camera_timestamp_ns = static_cast<std::int64_t>(std::llround(now_s_ * 1e9));
      t.stale = stale_[f];
      t.fresh = fresh_[f] && !stale_[f];
    }
    twist_fx_n_ = 0;
    in.arm.wrist = wrist_;
    in.arm.fingertip_position_m = {Vec3{-o_.fingertip_lever_m, 0, 0},
                                   Vec3{o_.fingertip_lever_m, 0, 0}};
    in.arm.active_segment_id = segment_.segment_id;
    in.arm.segment_done = segment_done_;
    in.arm.holding = wrist_held_ || holding_once_;
    holding_once_ = false;
    in.arm.deadman = deadman_;
    in.now_s = now_s_;
    return in;
  }

  // Carries out the command and advances one frame.
  void apply(const ControllerOutput& out) {
    const Command& c = out.command;
    switch (c.kind) {
      case CommandKind::kMoveTo:
        segment_ = c.move_to;
        segment_names_.emplace_back(c.move_to.name);
        segment_frames_ = 0;
        segment_done_ = false;
        wrist_held_ = false;
        if (!c.move_to.keep_finger_velocities) finger_velocity_.fill({});
        break;
      case CommandKind::kFingerVelocities:
        finger_velocity_ = c.finger_velocities.velocity_mps;
        break;
      case CommandKind::kHold:
        finger_velocity_.fill({});
        opening_m_.fill(0.0);
        wrist_held_ = true;
        break;
      case CommandKind::kOpen:
        finger_velocity_.fill({});
        opening_m_.fill(c.open.distance_m);
        open_speed_ = c.open.speed_mps;
        break;
      case CommandKind::kStop:
        finger_velocity_.fill({});
        opening_m_.fill(0.0);
        wrist_held_ = true;
        stopped_ = true;
        break;
      case CommandKind::kNone:
        break;
    }
    step_physics();
  }

 private:
  static constexpr double kContactN = 0.02;

  double pole_force(std::size_t tip) const {
    return gap_mm_[tip] < 0 ? -gap_mm_[tip] * o_.stiffness_n_per_mm : 0.0;
  }

  void step_physics() {
    const double dt = o_.dt_s;
    now_s_ += dt;
    if (segment_.segment_id != 0 && !segment_done_ && !wrist_held_) {
      ++segment_frames_;
      const Vec3 to = segment_.target.position_m - wrist_.position_m;
      const double d = norm(to);
      const double step = segment_.max_speed_mps * dt;
      wrist_.position_m =
          d <= step ? segment_.target.position_m : wrist_.position_m + (step / d) * to;
      const double dyaw = segment_.target.yaw_rad - wrist_.yaw_rad;
      const double ystep = segment_.max_yaw_rate_rps * dt;
      wrist_.yaw_rad = std::abs(dyaw) <= ystep ? segment_.target.yaw_rad
                                               : wrist_.yaw_rad + std::copysign(ystep, dyaw);
      segment_done_ = d <= step && std::abs(dyaw) <= ystep;
    }
    for (std::size_t f = 0; f < kFingertips; ++f) {
      if (opening_m_[f] > 0) {
        const double s = std::min(open_speed_ * dt, opening_m_[f]);
        opening_m_[f] -= s;
        gap_mm_[f] += 1000.0 * s;
      } else {
        // Only the squeeze component changes the indentation of this simple contact.
        gap_mm_[f] -= 1000.0 * finger_velocity_[f].z * dt;
      }
    }
  }

  Options o_;
  Script script_;
  double now_s_ = 0;
  WristPose wrist_;
  MoveTo segment_;
  std::vector<std::string> segment_names_;
  int segment_frames_ = 0;
  bool segment_done_ = false;
  bool wrist_held_ = false;
  bool deadman_ = false;
  bool holding_once_ = false;
  bool stopped_ = false;
  std::array<double, kFingertips> gap_mm_{};
  std::array<double, kFingertips> opening_m_{};
  double open_speed_ = 0;
  std::array<Vec3, kFingertips> finger_velocity_{};
  std::array<std::array<ElementReading, kElements>, kFingertips> readings_{};
  std::array<Vec3, kElements> normals_{};
  std::array<std::array<Vec3, kElements>, kFingertips> injected_{};  // dx, dy, set flag
  double twist_fx_n_ = 0;
  std::array<std::uint64_t, kFingertips> sequence_{};
  std::array<bool, kFingertips> stale_{};
  std::array<bool, kFingertips> fresh_{true, true};
};

// What a run produced, for whole-sequence checks.
struct Trace {
  std::vector<Event> events;
  std::vector<Command> commands;  // every command other than kNone, in order
  std::vector<Phase> phase_at_command;
  int updates = 0;
  std::size_t dropped_events = 0;
};

inline Trace run(GraspMoveTwistController& ctl, ScriptedRig& rig, int max_updates = 20000) {
  Trace t;
  for (int i = 0; i < max_updates && !ctl.done(); ++i) {
    const ControllerInput in = rig.next_input();
    const ControllerOutput out = ctl.update(in);
    for (const Event& e : out.events)
      t.events.push_back(e);
    t.dropped_events += out.events.dropped();
    if (out.command.kind != CommandKind::kNone) {
      t.commands.push_back(out.command);
      t.phase_at_command.push_back(out.phase);
    }
    rig.apply(out);
    ++t.updates;
  }
  return t;
}

// One line per event, in the words of docs/control.md: "PHASE LIFT", "TWIST_CYCLE 2",
// "CAP_TIGHT 3", "RECOMPRESS tip0".
inline std::string describe(const Event& e) {
  std::ostringstream s;
  s << to_string(e.kind);
  switch (e.kind) {
    case EventKind::kPhase:
      s << ' ' << e.text;
      break;
    case EventKind::kTwistCycle:
    case EventKind::kCapTight:
      s << ' ' << e.cycle;
      break;
    case EventKind::kRecompress:
    case EventKind::kOver:
    case EventKind::kStaleHold:
    case EventKind::kGraspClassified:
    case EventKind::kReleaseClassified:
      s << " tip" << static_cast<int>(e.fingertip);
      break;
    default:
      break;
  }
  return s.str();
}

inline std::vector<std::string> describe(const std::vector<Event>& events) {
  std::vector<std::string> out;
  for (const Event& e : events)
    out.push_back(describe(e));
  return out;
}

inline std::vector<std::string> segment_names(const Trace& t) {
  std::vector<std::string> out;
  for (const Command& c : t.commands) {
    if (c.kind == CommandKind::kMoveTo) out.emplace_back(c.move_to.name);
  }
  return out;
}

inline const Event* find(const std::vector<Event>& events, EventKind kind) {
  for (const Event& e : events) {
    if (e.kind == kind) return &e;
  }
  return nullptr;
}

}  // namespace tactile::control::testing
