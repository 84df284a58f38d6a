#pragma once

// Ground truth for every camera frame (docs/rig.md, "Ground truth"): the true per-element
// forces, shear displacements and stick/slide state, the cap's pose and angle. Mirrors the
// wire's GroundTruth message without depending on Protobuf.
#include <algorithm>
#include <array>
#include <cstdint>

#include "tactile/rig/world.hpp"

namespace tactile::rig {

struct ElementTruth {
  std::uint32_t id = 0;
  bool contact = false;  // the feeler touches the cap
  bool visible = false;  // in contact with F_z at or above the sensor's contact threshold
  double fz_n = 0;       // true normal force
  double fx_n = 0;       // true shear force along x_f
  double fy_n = 0;       // along y_f
  double ux_mm = 0;      // true shear displacement of the element's spot
  double uy_mm = 0;
  // The slip rule of docs/rig.md: the tip slid over the cap by more than the slip threshold
  // in this frame; or the cap surface moved over the element's base by more than the threshold
  // while the element was already sliding or loaded beyond the partial-slip ratio of its
  // static limit (Cattaneo-Mindlin micro-slip at the feeler's rim).
  bool sliding = false;
  std::uint32_t releases = 0;  // stick-slip releases within the frame interval
  double slip_mm = 0;          // distance the tip slid over the cap in the frame
  double surface_mm = 0;       // cap surface motion over the element's base in the frame
  double load_ratio = 0;       // |F_t| / (mu_s F_n) at the end of the frame
};

struct FingertipTruth {
  std::uint64_t camera_frame_id = 0;
  std::int64_t camera_timestamp_ns = 0;
  std::array<ElementTruth, kElementsPerFingertip> elements{};
};

struct GroundTruth {
  double sim_time_s = 0;
  std::array<FingertipTruth, kFingertips> fingertips{};
  Vec3 object_position_m;
  double cap_yaw_rad = 0;
  double cap_angle_deg = 0;
  bool cap_tight = false;
  bool dropped = false;
  bool cap_on_bottle = false;
  CapPlace place = CapPlace::kOnTable;
  std::uint32_t twist_cycle = 0;  // the controller's cycle as the rig last saw it (caller sets)
};

// The grip's truth at one instant (docs/rig.md, "The grip's truth"), for the report's `grip`.
struct GripTruth {
  // The least total normal force per fingertip that holds the cap now (grip_needed_n): its
  // weight, the wrist's actual acceleration (vibration included), on the thread the thread's
  // resisting torque, and a disturbance's external force and added mass.
  double needed_n = 0;
  // The grip applied: each fingertip's total normal force on the cap.
  std::array<double, kFingertips> applied_n{};
  // Held by the fingers: both fingertips touch the cap and nothing else holds it (CapPlace::kFree:
  // off the table, the bottle's neck and the thread; and not anchored, cap.held_to_table).
  bool held = false;
  // How far the cap slid against the fingertips in the frame: per fingertip, the distance its
  // in-contact elements' tips slid over the cap, averaged with their normal forces as weights;
  // the larger of the two. The feelers' elastic deflection is not sliding and does not count.
  double slide_mm = 0;
  // The grip the report scores (its `grip` ratios, the series' grip_applied_N): the smaller
  // fingertip's, the one that lets go first.
  double scored_n() const noexcept { return std::min(applied_n[0], applied_n[1]); }
};
// From the world now and the frame's truth just taken from it (TruthRecorder::take).
GripTruth grip_truth(const World& world, const GroundTruth& truth);

// A fragile object's truth (cap.crush_force_n; docs/rig.md, "Disturbances and fragile objects"):
// broken from the first frame whose applied grip, the larger fingertip's total normal force on
// the cap, exceeds the crush force; and the largest grip applied over the run. Allocates nothing.
struct CrushTruth {
  double crush_force_n = 0;  // 0: not fragile, never broken
  double peak_grip_n = 0;
  bool broken = false;
  double broken_at_s = 0;  // the frame's time, when broken
  // One frame's grip truth, at `t_s`.
  void add(double t_s, const GripTruth& grip) noexcept;
};

// Builds the truth of each frame from the world and keeps the slip-episode state. No
// allocation; take() clears the world's per-frame accumulators.
class TruthRecorder {
 public:
  // `visible_fz_n`: the force of the sensor's contact threshold, g(contact.on);
  // `partial_slip_ratio`: the load ratio beyond which a moving contact counts as slipping.
  TruthRecorder(double visible_fz_n, double partial_slip_ratio)
      : visible_fz_n_(visible_fz_n), partial_slip_ratio_(partial_slip_ratio) {}

  // `slip_threshold_mm`: the per-frame displacement the measurement calls a slip at this
  // moment (dr, or dr times the twist factor); an episode continues while the cap surface moves
  // over an element's base by more than it.
  const GroundTruth& take(World& world, std::uint64_t frame_id, double slip_threshold_mm);
  const GroundTruth& last() const { return truth_; }

 private:
  double visible_fz_n_;
  double partial_slip_ratio_;
  GroundTruth truth_;
};

}  // namespace tactile::rig
