#pragma once

// The simulated world of the rig (docs/rig.md): an arm whose wrist follows trajectory segments
// with bounded acceleration and vibration, two opposed fingertips with 41 rubber sensing
// elements each on a hemispherical dome, a cap on a table, and a bottle whose neck lets the cap
// turn freely up to free_turn_deg before resisting with a stiff, rising torque.
//
// Pure: no I/O, no clocks, no allocation after construction. Time is an argument: step(dt)
// advances the world by dt with the command last applied.
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "tactile/curve.hpp"
#include "tactile/geometry.hpp"

namespace tactile::rig {

inline constexpr std::size_t kFingertips = 2;
inline constexpr std::size_t kElementsPerFingertip = 41;

// --- parameters (every one has a documented default: docs/rig.md, scenario keys) -------------

struct CapParams {
  double mass_kg = 0.010;
  double radius_m = 0.015;
  double height_m = 0.016;
  double friction = 0.8;        // static Coulomb coefficient mu_s between feeler and cap
  double kinetic_ratio = 0.5;   // mu_k = kinetic_ratio * mu_s
  double inertia_factor = 0.6;  // I = inertia_factor * m * R^2 (a shell with a top)
  double x_m = 0.35;            // resting place on the table
  double y_m = -0.10;
  double table_friction = 0.4;
  // A negative case of the sweep (docs/slip.md): the cap is held to the table where it rests,
  // by a stiff anchor (the table's own stiffness and damping, horizontally and upward) that no
  // grip within F2 can pull it out of. It can still turn.
  bool held_to_table = false;
  // A fragile object (docs/rig.md, "Disturbances and fragile objects"): the grip, the larger
  // fingertip's total normal force on the cap, at which it breaks. 0: not fragile.
  double crush_force_n = 0;
};

struct BottleParams {
  double x_m = 0.35;
  double y_m = 0.10;
  double height_m = 0.18;                    // neck top above the table (the cap seats here)
  double free_turn_deg = 240.0;              // the cap turns freely this far, then tightens
  double free_torque_nm = 0.002;             // thread friction while turning freely
  double tight_stiffness_nm_per_rad = 50.0;  // slope of the rising torque past free_turn
  double capture_radius_m = 0.004;  // the neck's chamfer centres a cap this close to its axis
  bool tighten_clockwise = true;    // seen from above (yaw decreasing): a right-hand thread
  // A negative case of the sweep (docs/slip.md): the bottle really stands this far from (x_m,
  // y_m), the place the controller is given.
  double displaced_x_m = 0;
  double displaced_y_m = 0;
};

struct ArmParams {
  double max_accel_mps2 = 0.5;        // bound on the wrist's linear acceleration
  double stop_decel_mps2 = 2.0;       // Hold and Stop brake the wrist this hard
  double max_yaw_accel_rps2 = 2.0;    // bound on the wrist's angular acceleration
  double stop_yaw_decel_rps2 = 20.0;  // Hold and Stop brake the wrist's turn this hard
  double vibration_m = 0.0002;        // amplitude of the vertical wrist vibration
  double vibration_hz = 12.0;
  double vibration_rise_s = 0.05;          // the vibration follows the arm's speed this fast
  double vibration_full_speed_mps = 0.05;  // the amplitude is reached at this wrist speed
  double finger_accel_mps2 = 1.0;          // bound on each fingertip's acceleration
  double finger_open_m = 0.008;            // initial gap between each fingertip and the cap surface
  Vec3 start_position_m{0.35, -0.10, 0.25};  // initial grasp centre
  double start_yaw_rad = 0.0;
};

struct FingertipParams {
  double dome_radius_m = 0.010;
  // Polar angle of each ring of elements on the dome (centre, 8, 16, 16 elements).
  std::array<double, 4> ring_polar_deg{0.0, 10.0, 20.0, 30.0};
  double normal_stiffness_npm = 1500.0;  // F_n = k_n * indentation (+ damping)
  double normal_damping_nspm = 0.3;
  double tangential_damping_nspm = 0.3;  // while sticking
  // The feeler's tangential law per fingertip axis: F = f(s) with s the tip's deflection in mm
  // (odd). The rig uses the sensor's own calibrated shear curve, so the spot shift the camera
  // sees is exactly the deflection.
  PiecewiseLinear shear_curve{{0.0, 0.02, 0.08}, {0.0, 0.05, 0.4}};
};

// External disturbances of the cap (docs/rig.md, "Disturbances and fragile objects"), each off
// while its magnitude is 0. A start time is on the world's clock; a start not known yet (a time
// into a stage of the task, World::start_disturbance sets it when the stage begins) is infinite.
inline constexpr double kNotYet = std::numeric_limits<double>::infinity();

// A pull on the cap: force_n along `direction` (world frame, unit), from start_s for duration_s;
// rising linearly over ramp_s (0: a step).
struct PullParams {
  double force_n = 0;
  Vec3 direction{0, 0, -1};
  double start_s = kNotYet;
  double ramp_s = 0;
  double duration_s = kNotYet;
};
// A load added to the cap: its mass grows by added_kg from start_s on (moving with the cap).
struct MassStepParams {
  double added_kg = 0;
  double start_s = kNotYet;
};
// A knock: the impulse impulse_ns along `direction` (world frame, unit), as a constant force
// over duration_s from start_s.
struct KnockParams {
  double impulse_ns = 0;
  Vec3 direction{1, 0, 0};
  double start_s = kNotYet;
  double duration_s = 0.005;
};
enum class DisturbanceKind : std::uint8_t { kPull, kMassStep, kKnock };
struct DisturbanceParams {
  PullParams pull;
  MassStepParams mass_step;
  KnockParams knock;
};

struct WorldParams {
  CapParams cap;
  BottleParams bottle;
  ArmParams arm;
  FingertipParams fingertip;
  DisturbanceParams disturbance;
  double gravity_mps2 = 9.81;
  double table_stiffness_npm = 200000.0;
  double table_damping_nspm = 20.0;
  double seat_stiffness_npm = 200000.0;  // the bottle neck under the cap
  double seat_damping_nspm = 20.0;
  double slip_speed_eps_mps = 0.001;  // regularisation of table and thread friction
};

// The external force's impulse on the cap over [t0_s, t1_s] (N s, world frame): the pull's and
// the knock's, integrated exactly, so that a step of any length carries its share.
Vec3 external_impulse_ns(const DisturbanceParams& d, double t0_s, double t1_s);
// The cap's mass at `t_s`: its own, plus the load added by then.
double cap_mass_kg(const WorldParams& p, double t_s);

// --- commands (the arm controller's side of ArmCommand) ----------------------------------------

enum class CommandKind : std::uint8_t { kNone, kMoveTo, kFingerVelocities, kHold, kOpen, kStop };

struct ArmCommand {
  CommandKind kind = CommandKind::kNone;
  // kMoveTo
  std::uint32_t segment_id = 0;
  Vec3 target_position_m;
  double target_yaw_rad = 0;
  double max_speed_mps = 0;
  double max_yaw_rate_rps = 0;
  bool keep_finger_velocities = false;
  // kFingerVelocities: each fingertip's velocity in its own fingertip frame
  std::array<Vec3, kFingertips> finger_velocity_mps{};
  // kOpen
  double open_speed_mps = 0;
  double open_distance_m = 0;
};

// --- state ---------------------------------------------------------------------------------

// One sensing element: geometry (fixed) and contact state.
struct Element {
  // Fixed: the feeler tip on the dome, in the fingertip frame, relative to the dome's apex,
  // and the unit inward normal (the direction that presses it harder).
  Vec3 tip_f;
  Vec3 normal_f;
  // Contact state.
  double indentation_m = 0;
  double fn_n = 0;               // normal force of the rubber spring (what the spot shows)
  std::array<double, 2> s_mm{};  // tangential tip deflection along x_f, y_f (the spot shift)
  std::array<double, 2> ft_n{};  // tangential spring force f(s) along x_f, y_f
  bool contact = false;
  bool sliding = false;  // the last step released the tip from static friction
  // Accumulated since the last take_frame(): stick-slip releases and the tangential motion of
  // the cap surface over the element's base (mm, along x_f, y_f).
  std::uint32_t frame_releases = 0;
  double frame_slip_mm = 0;  // distance the tip slid over the surface in those releases
  std::array<double, 2> frame_surface_mm{};
};

struct Fingertip {
  // Apex (centre element) position in the wrist frame and its velocity in the fingertip frame.
  Vec3 offset_w;
  Vec3 velocity_f;
  Vec3 commanded_velocity_f;
  std::array<Element, kElementsPerFingertip> elements{};
  // World frame axes of the fingertip frame and apex position.
  Vec3 x_f, y_f, z_f;
  Vec3 apex_world;
};

enum class CapPlace : std::uint8_t { kOnTable, kFree, kOnBottle, kThreaded };
const char* to_string(CapPlace p);

struct CapState {
  Vec3 position_m;  // centre of the cylinder
  Vec3 velocity_mps;
  double yaw_rad = 0;
  double yaw_rate_rps = 0;
  CapPlace place = CapPlace::kOnTable;
  double seat_yaw_rad = 0;  // yaw when it seated on the bottle
  double angle_deg = 0;     // turned on the thread in the tightening direction since seating
  bool tight = false;       // angle_deg passed free_turn_deg
  bool lifted = false;      // has been off the table by more than 5 mm
  bool dropped = false;     // fell back to the table or out of the grip
  double thread_torque_nm = 0;
};

struct ArmState {
  Vec3 position_m;  // grasp centre without vibration
  Vec3 velocity_mps;
  Vec3 accel_mps2;  // over the last step, without vibration (the grip's truth reads it)
  double yaw_rad = 0;
  double yaw_rate_rps = 0;
  double vibration_envelope = 0;
  Vec3 vibration_m;  // current vibration offset
  std::uint32_t active_segment_id = 0;
  bool segment_done = true;
  bool holding = false;
  bool stopped = false;
};

// The least grip that holds (docs/rig.md, "The grip's truth"): the total normal force each
// fingertip must press with for static friction (mu_s) to carry the cap at acceleration
// `accel_mps2` against gravity and to transmit `torque_nm` about its axis. The two fingertips
// share the cap's weight and inertia equally; the torque is a couple at the cap's radius; each
// fingertip's tangential demand is the vector sum of its shares. The load along `squeeze_axis`
// (a horizontal unit vector from one fingertip to the other) is carried by the normal forces.
// With a disturbance: the cap's mass then (`mass_kg`) and the external force on it
// (`external_force_n`, world frame), which the fingers must hold against as well.
double grip_needed_n(const WorldParams& p, Vec3 accel_mps2, Vec3 squeeze_axis, double torque_nm,
                     double mass_kg, Vec3 external_force_n);
// The same for the cap's own mass and no external force.
inline double grip_needed_n(const WorldParams& p, Vec3 accel_mps2, Vec3 squeeze_axis,
                            double torque_nm) {
  return grip_needed_n(p, accel_mps2, squeeze_axis, torque_nm, p.cap.mass_kg, {});
}

// Whether the hand can hold the cap within F2, from the world's parameters alone (docs/rig.md,
// "Holding within F2"): the grip each fingertip needs to carry the cap's weight and its peak
// acceleration on friction, against the grip it can press with no element beyond F2.
struct HoldNeed {
  // The wrist's acceleration bound (arm.max_accel_mps2) plus the vibration's peak,
  // (2 pi f)^2 A, both taken along gravity.
  double peak_accel_mps2 = 0;
  // Per fingertip: m (g + peak_accel) / (2 mu_s), grip_needed_n() of the peak along gravity;
  // with disturbances, the largest of them as well (docs/rig.md, "Disturbances and fragile
  // objects"): the heavier mass after a mass step, and the pull's or the knock's force, whichever
  // asks for more, its vertical part adding to the load and its horizontal part across the
  // squeeze.
  double grip_needed_n = 0;
  // Per fingertip: the sum of the elements' normal forces on the cap when the most pressed one
  // (the apex) carries F2, from the dome's element layout against the cap's cylinder.
  double grip_allowed_n = 0;
  bool holdable = false;  // grip_needed_n <= grip_allowed_n
};
HoldNeed hold_need(const WorldParams& p, double f2_n);

// The world. Construction allocates; step() and apply() allocate nothing and never throw.
class World {
 public:
  explicit World(const WorldParams& p);

  const WorldParams& params() const { return p_; }

  // Applies an arm command from now on (MoveTo, FingerVelocities, Hold, Open, Stop). A command
  // with a non-finite number is refused (returns false) and changes nothing.
  bool apply(const ArmCommand& c) noexcept;
  // Advances by dt seconds (semi-implicit Euler). Returns false, keeping the last finite state
  // of arm and cap and letting go of every feeler, if anything became non-finite (never seen;
  // guarded so that no NaN can leave the physics).
  bool step(double dt) noexcept;

  // Where the bottle's axis really stands: its place plus the displacement.
  double bottle_x_m() const { return p_.bottle.x_m + p_.bottle.displaced_x_m; }
  double bottle_y_m() const { return p_.bottle.y_m + p_.bottle.displaced_y_m; }

  double time() const { return t_; }
  const ArmState& arm() const { return arm_; }
  const CapState& cap() const { return cap_; }
  const Fingertip& fingertip(std::size_t i) const { return tips_[i]; }
  // Grasp centre including vibration, world frame.
  Vec3 wrist_actual() const { return arm_.position_m + arm_.vibration_m; }
  // Its acceleration: the last step's, plus the vibration's (its envelope taken as constant, as
  // the feelers' bases move with it).
  Vec3 wrist_accel_actual() const noexcept;

  // The cap's mass now (its own plus a load added, DisturbanceParams::mass_step), and the
  // external force on it over the last step (the pull's and the knock's, world frame).
  double cap_mass_kg() const noexcept;
  Vec3 external_force_n() const noexcept { return external_force_n_; }
  // A disturbance timed from a stage of the task starts at `t_s` (the run sets it when the stage
  // begins); the first call for a kind counts.
  void start_disturbance(DisturbanceKind kind, double t_s) noexcept;

  // Clears the per-frame accumulators (releases, surface motion) after a frame was taken.
  void clear_frame_accumulators() noexcept;

  // Unit inward normals of the 41 elements in the fingertip frame (same for both fingertips).
  std::array<Vec3, kElementsPerFingertip> element_normals() const;

 private:
  void update_arm(double dt) noexcept;
  void update_fingers(double dt) noexcept;
  void place_fingertips() noexcept;
  // The motion of the feelers' bases this step: the wrist with its vibration, and each
  // fingertip's own velocity (world frame).
  struct BaseMotion {
    Vec3 wrist;
    Vec3 vibration_velocity;
    std::array<Vec3, kFingertips> finger_velocity{};
  };
  BaseMotion base_motion(double dt) const noexcept;
  // Velocity of the cap's surface at `pe` relative to the base of fingertip i's feeler there.
  Vec3 relative_velocity(const BaseMotion& b, std::size_t i, Vec3 pe) const noexcept;
  void contact_forces(const BaseMotion& b, Vec3& force, double& torque, double dt) noexcept;
  // No feeler of the fingertip can touch the cap's side this step (a bounding test on its apex:
  // every feeler lies within reach_m_ of it).
  bool out_of_reach(const Fingertip& t) const noexcept;
  void update_cap_place() noexcept;
  // The pull's and the knock's force over the step [t, t + dt] into `force` (external_force_n).
  void add_external_force(Vec3& force, double dt) noexcept;
  void update_tangential(const BaseMotion& b, double dt) noexcept;
  // What the table and the bottle neck add to the cap this step.
  struct Supports {
    double table_n = 0;  // normal force of the table (for its friction)
    double friction_torque_max = 0;
    double thread_torque = 0;
  };
  Supports support_forces(Vec3& force, double inertia) const noexcept;
  void integrate_cap(Vec3 force, double torque, const Supports& s, double inertia,
                     double dt) noexcept;
  bool state_finite() const noexcept;
  void roll_back(const ArmState& arm, const CapState& cap, double dt) noexcept;
  double shear_force(double s_mm) const noexcept { return p_.fingertip.shear_curve.odd(s_mm); }
  void release_to(Element& e, double force_n) const noexcept;

  WorldParams p_;
  double t_ = 0;
  ArmState arm_;
  ArmCommand move_;  // the active MoveTo (or the hold target)
  bool has_move_ = false;
  std::array<Fingertip, kFingertips> tips_{};
  std::array<double, kFingertips> open_left_m_{};  // distance an Open still has to go
  bool opening_ = false;
  double open_speed_ = 0;
  CapState cap_;
  double mu_k_ = 0;
  double reach_m_ = 0;  // the farthest feeler tip from the apex
  // Whether any feeler of fingertip i is in contact (kept by contact_forces).
  std::array<bool, kFingertips> touching_{};
  Vec3 external_force_n_;  // the pull's and the knock's over the last step
};

}  // namespace tactile::rig
