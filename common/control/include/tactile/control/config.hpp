#pragma once

// Every threshold, gain, speed and place the control core uses, with its default. The table in
// docs/control.md lists them with units; keep the two in step.
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>

#include "tactile/geometry.hpp"

namespace tactile::control {

enum class Task : std::uint8_t {
  kGraspMoveTwist,    // Phase I then Phase II at the place where the cap was released
  kGraspMoveRelease,  // Phase I only
  kTwistOnly,         // Phase II only, with the wrist pose of the first update as reference
};
const char* to_string(Task t);

// Which slip detector raises SLIP (docs/slip.md, "The detectors"): the paper's rule, the field
// detector (rigid-motion residual, friction-cone load, arm motion), or the learned combiner of the
// field detector's signals (a small boosted-tree model compiled in, trained by slip_train).
enum class SlipDetectorKind : std::uint8_t { kPaper, kField, kLearned };
const char* to_string(SlipDetectorKind k);
// The field and learned detectors decide Phase I's lift and lowering from the load transfer;
// the paper's rule keeps the paper's decisions.
inline bool beyond_paper(SlipDetectorKind k) {
  return k != SlipDetectorKind::kPaper;
}
std::optional<SlipDetectorKind> slip_detector_from_string(std::string_view name);
// The names slip_detector_from_string accepts, for error messages.
inline constexpr const char* kSlipDetectorNames = "paper, field or learned";

// Which grip the controller keeps (docs/control.md): the paper's (close to F1, re-compress on
// SLIP, back off on OVER) or the margin grip (close to a light contact, then a force servo on the
// least grip that holds with a margin, GripLaw). Every run names it beside the slip detector.
enum class GripKind : std::uint8_t { kPaper, kMargin };
const char* to_string(GripKind k);
std::optional<GripKind> grip_from_string(std::string_view name);
// The names grip_from_string accepts, for error messages.
inline constexpr const char* kGripNames = "paper or margin";

struct Config {
  Task task = Task::kGraspMoveTwist;

  // --- flags (paper section IV) ------------------------------------------------------------
  // F1: an element pressed harder than this raises TOUCH and stops the finger. Chosen for a
  // normal curve whose full scale is about 3 N: a firm hold on a light cap, far from F2.
  double f1_n = 0.5;
  // F2: an element pressed harder than this raises OVER: stop squeezing, back off.
  double f2_n = 2.5;
  // dr: an in-contact element slips when its per-frame centroid displacement exceeds this
  // (the paper's 0.004 mm).
  double dr_mm = 0.004;
  // dr is multiplied by this in Phase II (the paper's 1.3).
  double twist_dr_factor = 1.3;
  // The gravity direction in the fingertip frame when the hand is upright. Only its x and y
  // components act: the displacement has none along z_f.
  Vec3 gravity_axis{0.0, 1.0, 0.0};
  // The slip detector: kLearned, the learned combiner of the field detector's signals, wins on
  // the sweep (docs/slip.md, "Results"); kPaper is the paper's rule (an element slips when its
  // centroid moves more than dr in a frame) and reproduces the paper's experiment.
  SlipDetectorKind slip_detector = SlipDetectorKind::kLearned;
  // The grip (key `grip`): kPaper reproduces the paper; kMargin is the margin grip (GripLaw, its
  // parameters below).
  GripKind grip = GripKind::kPaper;
  // The field detector's parameters (docs/slip.md). An element moving more than dr counts as
  // slipping only when loaded beyond this fraction of the friction estimate (Cattaneo-Mindlin
  // partial slip), or when it was slipping.
  double field_partial_slip_ratio = 0.1;
  // An element loaded beyond this fraction of the friction estimate is at the cone's edge: a
  // slipping element stays slipping there while the contact or the arm moves.
  double field_edge_ratio = 0.7;
  // A fall of the load ratio |F_t| / F_n by more than this fraction of mu in one frame, from the
  // cone's edge, is a breakaway.
  double field_drop_ratio = 0.1;
  // The friction estimate starts here and rises with the loads the elements carry (a load ratio
  // |F_t| / F_n never exceeds mu). Not the cap's friction: a starting point, the middle of the
  // range the detector is meant for (0.4-1.2).
  double field_mu_initial = 0.7;
  // Elements pressed less than this carry no usable load ratio.
  double field_min_fz_n = 0.05;
  // The arm moves when the wrist's reported speed or yaw rate exceeds these.
  double field_arm_speed_mps = 0.002;
  double field_arm_yaw_rate_rps = 0.02;
  // With the field detector the lift and the lowering classify from the load transfer: the shear
  // load along gravity the fingertips carry (docs/slip.md, "Decisions on the field detector").
  // A change of the load per fingertip beyond this is the cap's weight arriving (N; a 3 g cap
  // brings 0.015 N to each fingertip).
  double load_transfer_n = 0.006;
  // The lift decides after this long: the cap carried (load arrived, the contact mostly sticks)
  // is a grasp; a contact slipping in most frames while the arm rises is a cap held from below.
  double lift_confirm_s = 0.2;
  // A slip is classified only when its displacement along gravity exceeds this in magnitude.
  // 0 is the paper's rule (the sign alone decides).
  double direction_deadband_mm = 0.0;

  // --- finger speed estimator (paper Fig. 6) -----------------------------------------------
  double approach_speed_mps = 0.005;    // SEARCH: closing speed along z_f
  double recompress_gain_mps = 0.003;   // speed added along the inward normal per slip frame
  double recompress_duration_s = 0.05;  // a re-compression lasts this long after the last slip
  // A fingertip whose largest F_z has reached this fraction of F2 does not re-compress: it holds.
  // Re-compression speeds add up frame by frame; a grip pushed to F2 trips OVER, backs off to
  // just under F2, and the next slip pushes it over again within a frame (a chatter at F2 seen in
  // real-time runs with a light F1). 1 is the paper's rule: OVER alone stops the squeeze.
  double recompress_max_f2_fraction = 0.9;
  double backoff_speed_mps = 0.001;    // OVER: speed away from the object along -z_f
  double max_finger_speed_mps = 0.01;  // bound on every fingertip velocity's magnitude

  // --- the margin grip (grip: margin; docs/control.md, "The margin grip") --------------------
  // TOUCH: a fingertip whose total F_z (the sum over its in-contact elements) exceeds this. Well
  // under F1 and far above the sensor's force noise (about 0.003 N per element in the rig).
  double grip_touch_n = 0.05;
  // The least target (N per fingertip): the fingertips stay on the object, above the touch.
  double grip_min_n = 0.1;
  // Without the loading phase (below): the least target from the grasp to the lift's end (N per
  // fingertip), before the lift has weighed the object (with grip_min_n alone the learned
  // detector saw the cap slip through most of the lift and put it back in 20 of the seed-20
  // sweep's 32 normal scenarios). With it: the most the loading phase's demand asks (an object
  // anchored to the table pulls back as hard as the fingertips hold it).
  double grip_lift_n = 0.8;
  // The lift's loading phase (a person's: the grip rises with the load before the object leaves
  // the table): the arm first rises grip_loading_distance_m at grip_loading_speed_mps, slowly
  // enough for the grip to follow the load as the fingertips' rubber takes the weight; then the
  // lift. With it the grasp needs no floor: grip_lift_n is for a lift without one (speed 0).
  double grip_loading_speed_mps = 0.001;
  double grip_loading_distance_m = 0.0003;
  // Grip over the least grip the load and the friction estimate ask for, minus 1, in the carry
  // (Johansson and Westling: 0.1-0.4) and in the twist (the thread's torque rises in a turn; 0.5
  // let the default scenario's turns slip two cycles in a row: tight declared a cycle early).
  double grip_margin = 0.25;
  double grip_twist_margin = 2.0;
  // The friction estimate mu_hat: its start (the low end of the range it is meant for, 0.4-1.2:
  // too much grip at first, not too little) and its bounds.
  double grip_mu_initial = 0.5;
  double grip_mu_min = 0.2;
  double grip_mu_max = 1.2;
  // After grip_safe_s without slip mu_hat rises by this fraction per second (the next slip says
  // how far is too far). 0: no probing. A probe needs a detector that sees a steady slide: with
  // the paper's rule the default cap slid out of the fingers at mu_hat 1.2 (true mu_s 0.8)
  // without one SLIP. A burst of slips (each within grip_safe_s of the last) lowers it to their
  // load ratio, by at most grip_mu_drop: incipient slip comes at any ratio.
  double grip_mu_rise_per_s = 0.0;
  double grip_mu_drop = 0.3;
  // A slip frame raises the target to this fraction above the grip (or the demand, the larger);
  // a grip already past that raise of the demand stays where it is.
  double grip_slip_step = 0.3;
  // No slip for this long is a safe while: the target relaxes toward the demand with relax_s.
  double grip_safe_s = 0.5;
  double grip_relax_s = 1.0;
  // A fingertip's tangential load is held this long (the arm's vibration, 5 Hz and up, passes
  // through its peak within it); also the weight estimate's time constant.
  double grip_load_window_s = 0.2;
  // The force servo: squeeze speed per newton of error, its bound, and the rate at which the
  // servo's reference follows the target.
  double grip_servo_gain_mps_per_n = 0.02;
  // The control period the gain is for: at a longer period (a slower camera) the gain falls in
  // proportion, so that each frame closes the same part of the error. The speed holds for a whole
  // period: at 30 fps the full gain closed more than the error in one frame and the grip rang
  // (0.35-0.52 N each frame of the carry), let the lowering's start slip the cap and release it
  // 6 cm above the bottle.
  double grip_servo_gain_period_s = 0.0125;
  double grip_servo_max_speed_mps = 0.005;
  double grip_force_rate_nps = 20.0;
  // Feed-forward: the arm's planned acceleration (the rig's arm.max_accel_mps2 default) and how
  // long before a segment's start or stop the grip rises for it.
  double grip_ff_accel_mps2 = 0.5;
  double grip_ff_lead_s = 0.3;
  // A grasp (either phase) moves the object only once the grip has reached its target, as a
  // person's grip force rises before the load does; at most this long past grasp_settle_s.
  // Only the margin grip waits: the paper's is at F1 when TOUCH comes. Without the wait, at 30 fps
  // (the servo's gain scaled down to the period) a turn began on a grip still rising, slipped at
  // once, and tightness was declared before the cap had turned.
  double grip_reach_timeout_s = 1.0;

  // --- places (world frame, m) -------------------------------------------------------------
  double cap_x_m = 0.35;
  double cap_y_m = -0.10;
  double bottle_x_m = 0.35;
  double bottle_y_m = 0.10;
  double grasp_yaw_rad = 0.0;      // wrist yaw while grasping and carrying
  double safe_height_m = 0.25;     // MOVE1 approaches the cap at this height
  double grasp_height_m = 0.01;    // grasp centre above the table when picking the cap up
  double carry_height_m = 0.25;    // MOVE3 lifts to, MOVE4 carries at this height
  double lower_limit_m = 0.0;      // MOVE5 goes no lower than this (the place is unknown)
  double retract_height_m = 0.02;  // MOVE6 and the final retreat rise this far

  // --- arm speeds ----------------------------------------------------------------------------
  double move_speed_mps = 0.10;     // MOVE1, MOVE2, MOVE6, approach and retreat of Phase II
  double lift_speed_mps = 0.05;     // MOVE3
  double carry_speed_mps = 0.08;    // MOVE4
  double lower_speed_mps = 0.02;    // MOVE5: slow enough to stop on the first contact
  double max_yaw_rate_rps = 1.0;    // every segment but the twist
  double twist_yaw_rate_rps = 0.5;  // TURN and RETURN

  // --- grasp and release ---------------------------------------------------------------------
  double grasp_settle_s = 0.1;    // after TOUCH on both fingertips, before "grasping ended"
  double open_speed_mps = 0.005;  // the gentle release
  double open_distance_m = 0.004;
  double open_settle_s = 0.05;  // after the open's nominal duration
  // After a stale hold, the arm stopped and started again under the object: the slips that
  // follow are the object's inertia, not its support. The lift's grasp/release and the
  // lowering's release are not classified for this long after the segment resumes.
  double resume_settle_s = 0.3;

  // --- Phase II (paper Fig. 8) -------------------------------------------------------------
  double twist_angle_rad = std::numbers::pi / 2.0;  // wrist turn per cycle (90 degrees)
  // Tightening turns the wrist clockwise seen from above (yaw decreases): a right-hand thread.
  bool tighten_clockwise = true;
  // Ns: slip detections in one cycle that mean "tight" (the paper's 8). A detection is one fresh
  // frame of one fingertip with SLIP raised, during the TURN step.
  std::uint32_t ns = 8;
  // A cycle "detected slip" when it counted at least this many detections; two such cycles in a
  // row mean "tight". 1 is the paper's rule.
  std::uint32_t cycle_slip_min = 1;
  std::uint32_t max_twist_cycles = 8;  // safety stop
  // With slip_detector field, tightness also from the twist torque the fingertips carry
  // (docs/slip.md, "Tightness from the twist torque"): tight once it has built above the turn's
  // free-turn level by tight_torque_rise_nm (and by tight_torque_rise_ratio of the level when that
  // is more) and then stops building. The sweep's thread turns freely at 0.002 N m, measured
  // steady to about 0.0003 N m.
  double tight_torque_rise_nm = 0.002;
  double tight_torque_rise_ratio = 1.0;
  // Time constant of the free-turn level (an average over the turn); the rise is judged from three
  // of them after the turn's start.
  double tight_level_s = 0.1;
  // The torque stopped building: no new peak for this long while the wrist turns (or the turn
  // ended). A new peak exceeds the last one by tight_plateau_fraction of the built torque.
  double tight_plateau_s = 0.02;
  double tight_plateau_fraction = 0.05;

  // --- timeouts and stale data ---------------------------------------------------------------
  double search_timeout_s = 5.0;    // SEARCH without TOUCH on both fingertips: abort
  double segment_timeout_s = 30.0;  // a MoveTo not done after this: abort
  // For the caller: a fingertip with no whole frame for this long is stale. The controller
  // itself only reads FingertipInput::stale.
  double stale_after_s = 0.1;
  // Abort after holding on stale data this long; 0 holds for ever.
  double stale_abort_s = 0.0;

  // Throws std::invalid_argument naming the first bad field and its value.
  void validate() const;
};

// The margin grip's lift begins with its loading phase (Config::grip_loading_speed_mps).
inline bool lift_loads_first(const Config& c) {
  return c.grip == GripKind::kMargin && c.grip_loading_speed_mps > 0 &&
         c.grip_loading_distance_m > 0;
}

// "slip detector: learned, grip: paper": which slip detector and which grip a controller of this
// configuration runs, as hand_node and the rig say it in their first lines.
std::string describe_controller(const Config& c);

}  // namespace tactile::control
