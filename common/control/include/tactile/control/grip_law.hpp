#pragma once

// The margin grip (docs/control.md, "The margin grip"): the least grip that holds, with a margin,
// instead of the paper's squeeze to F1. After the search has closed the fingers to a light
// contact, both fingertips squeeze with one velocity along z_f that drives the hand's grip (the
// mean of the fingertips' total normal forces) toward a target:
//
//   demand = (L + L_ff) / mu_hat * (1 + margin)   L: the larger fingertip's tangential load |sum
//                                                 F_t|, held over load_window; L_ff: the
//                                                 feed-forward of a planned acceleration
//   target: raised to the demand at once, by slip_step on a slip frame (a firm grip only on a
//           slide: three slip frames in a row, not in the lift's loading phase); relaxed toward
//           the demand with relax_s once no slip for safe_s
//   mu_hat: lowered to the load ratio L / F_n of a slip of the grip it set, by at most mu_drop
//           in one burst, and bounded above by the middle of that drop from then on; raised
//           slowly after safe_s (not in a turn); never under the largest ratio carried without
//           slip within load_window (Coulomb)
//   v_z = gain / n (F_ref - F)                    F_ref follows the target at most force_rate; n
//                                                 the elements in contact (the grip's stiffness)
//
// Pure: time is an argument; no allocation; every output finite.
#include <array>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

// What the sequencers say about the next moments (the controller fills it in).
struct GripContext {
  // Phase II: the twist's own margin and, ahead of a turn, the last turn's load.
  bool twist = false;
  // Phase I's lift and carry: the fingertips' load is the cap's weight (m_hat).
  bool carrying = false;
  // Phase I's grasp and lift: the weight is not known yet (at least grip_lift_n without the
  // loading phase).
  bool lifting = false;
  // The lift's loading phase: the weight arrives while the cap still rests on the table.
  bool loading = false;
  // The arm's own planned acceleration (a carrying segment's start or stop, the lift after the
  // grasp, a turn after the twist grasp) is at most grip_ff_lead_s away.
  bool accelerates_soon = false;
};

struct GripOutput {
  double squeeze_mps = 0;  // along z_f, the same for both fingertips (negative: open)
  // A fingertip's slip raised the target this update.
  std::array<bool, kFingertips> raised{};
};

class GripLaw {
 public:
  explicit GripLaw(const Config& cfg);

  // A new grasp (the fingers were stopped or opened): the target starts again from grip_min_n
  // and the reference from the grip measured next. The friction and weight estimates stay: it
  // is the same object.
  void reset() noexcept;
  // The tactile data went stale and the arm holds with the fingers stopped: the same grasp, so the
  // target, the reference and the loads stay; the time without data is neither a control step
  // (the next update's dt is 0) nor a safe while (it restarts at the next update).
  void pause() noexcept;

  GripOutput update(const Flags& flags, const std::array<FingertipInput, kFingertips>& inputs,
                    const GripContext& ctx, double now_s) noexcept;

  double target_n() const { return target_n_; }
  double reference_n() const { return ref_n_; }
  double grip_n() const { return grip_n_; }
  double mu_hat() const { return mu_hat_; }
  double weight_n() const { return weight_n_; }
  double demand_n() const { return demand_n_; }
  // The grip is within the servo's reach of its target (90 %): what the arm waits for before it
  // moves a grasped object (Config::grip_reach_timeout_s).
  bool reached() const noexcept;

 private:
  void observe(const Flags& flags, const std::array<FingertipInput, kFingertips>& inputs,
               const GripContext& ctx, double now_s, double dt) noexcept;
  double demand(const GripContext& ctx) const noexcept;
  void follow_slip(const Flags& flags, const GripContext& ctx, double now_s,
                   GripOutput& out) noexcept;
  void settle(const GripContext& ctx, double now_s, double dt) noexcept;

  Config cfg_;
  double mu_hat_;
  double weight_n_ = 0;      // the cap's weight as the fingertips carried it (m_hat g)
  double twist_load_n_ = 0;  // the largest tangential load of the last turn, per fingertip
  bool slipped_ = false;
  std::uint32_t slip_run_ = 0;                // fresh slip frames in a row, this one included
  double mu_before_slip_ = 0;                 // mu_hat when the current burst of slips began
  double mu_ceiling_ = 0;                     // mu_hat rises no further (0: no slip has bounded it)
  std::array<double, kFingertips> load_n_{};  // |sum F_t| on the latest fresh frame
  std::array<double, kFingertips> total_n_{};
  std::array<std::uint32_t, kFingertips> contacts_{};  // elements in contact, latest fresh frame
  std::array<double, kFingertips> peak_n_{};           // load held over grip_load_window_s
  std::array<double, kFingertips> peak_s_{};
  // The largest load ratio L_f / F_f of the window (fingertips pressed at least grip_min_n): a
  // lower bound on the friction.
  double ratio_peak_ = 0;
  double ratio_peak_s_ = 0;
  double grip_n_ = 0;
  double demand_n_ = 0;
  double target_n_ = 0;
  double ref_n_ = 0;
  bool has_ref_ = false;
  bool has_now_ = false;
  double last_now_s_ = 0;
  double last_slip_s_ = 0;
  bool twisting_ = false;  // the previous update was in a turn
  // Carried this long past the lift's planned acceleration; the object is weighed once that is
  // grip_load_window_s (weighed()): the lift's floor grip_lift_n is then no longer needed.
  double carried_s_ = 0;
  bool weighed() const noexcept { return carried_s_ >= cfg_.grip_load_window_s; }
  bool paused_ = false;     // pause() since the last update
  double safe_from_s_ = 0;  // no safe while counts before this (the update after a pause)
};

}  // namespace tactile::control
