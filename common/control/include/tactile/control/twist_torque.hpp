#pragma once

// Tightness from the twist torque (docs/slip.md, "Tightness from the twist torque"): while the cap
// turns freely the fingertips carry its small free-turn torque; once it meets its stop the torque
// builds while the wrist turns, then stops building (the contact saturates and slips, or the wrist
// stops). The rule declares tight when the torque has built clearly above the turn's free-turn
// level and then shows no new peak for tight_plateau_s, or when the turn's segment ends, the torque
// still built. Pure: time is an argument; no allocation.
#include "tactile/control/config.hpp"

namespace tactile::control {

class TwistTorquePlateau {
 public:
  explicit TwistTorquePlateau(const Config& cfg) noexcept : cfg_(cfg) {}

  // A new turn begins at t.
  void start(double t) noexcept;
  // One update in the turn: `torque_nm` the twist torque in the tightening direction (from a
  // fresh frame when `fresh`; otherwise ignored), `wrist_stopped` the turn's segment is done.
  // True when the torque stopped building: the cap is tight.
  bool update(double torque_nm, bool fresh, bool wrist_stopped, double t) noexcept;

  // The turn's free-turn level (N m), frozen once the torque builds.
  double level_nm() const { return level_nm_; }
  // The torque has built above the level (a peak is being followed).
  bool building() const { return building_; }
  double peak_nm() const { return peak_nm_; }

 private:
  double rise_nm() const noexcept;

  const Config& cfg_;
  double start_s_ = 0;
  double last_s_ = 0;
  bool has_level_ = false;
  double level_nm_ = 0;
  bool building_ = false;
  double peak_nm_ = 0;
  double peak_s_ = 0;
  double latest_nm_ = 0;
};

}  // namespace tactile::control
