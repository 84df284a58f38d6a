#pragma once

// The finger speed estimator (paper Fig. 6): each fingertip's velocity, in its own frame, from
// the flags and the mode.
//
//   kOff     velocity 0.
//   kSearch  approach along z_f until the fingertip touches (F_z > F1 or SLIP), then hold; the
//            touch is latched until the mode changes, so a dip under F1 does not restart it.
//   kMove    hold (0); on SLIP of a fresh frame, add recompress_gain along the inward normal of
//            the fingertip's element with the largest F_z to the current velocity, bounded by
//            max_finger_speed; the re-compression lasts recompress_duration after the last slip.
//            A fingertip whose largest F_z has reached recompress_max_f2_fraction of F2 holds
//            instead (no headroom left: squeezing on would only trip OVER).
//   OVER     in any driven mode, and before everything else: stop squeezing and back off along
//            -z_f at backoff_speed until the fingertip is under F2 again.
//
// With grip: margin, kMove is the margin grip's force servo instead (GripLaw): both fingertips
// squeeze along z_f at its speed; a slip that raises its target is a re-compression.
#include <array>
#include <cstddef>
#include <cstdint>

#include "tactile/control/config.hpp"
#include "tactile/control/grip_law.hpp"
#include "tactile/control/types.hpp"

namespace tactile::control {

enum class FingerAction : std::uint8_t { kIdle, kApproach, kHold, kRecompress, kBackOff };
const char* to_string(FingerAction a);

struct FingerSpeedOutput {
  std::array<Vec3, kFingertips> velocity_mps{};
  std::array<FingerAction, kFingertips> action{};
  // The fingertip started a re-compression this update (it was not re-compressing before).
  std::array<bool, kFingertips> recompress_started{};
  // The fingertip went over F2 this update (it was not over before).
  std::array<bool, kFingertips> over_started{};
};

class FingerSpeedEstimator {
 public:
  explicit FingerSpeedEstimator(const Config& cfg);

  // `inputs` supplies the normals; `now_s` is the controller's task time; `grip` what the
  // sequencers say of the next moments (the margin grip's feed-forward).
  FingerSpeedOutput update(FingerMode mode, const Flags& flags,
                           const std::array<FingertipInput, kFingertips>& inputs, double now_s,
                           const GripContext& grip = {}) noexcept;

  // The arm stopped the fingers (Hold, Open, Stop, or a MoveTo that does not keep them): the
  // current velocity is 0 and any re-compression is over.
  void reset() noexcept;
  // The arm holds because the tactile data went stale: the velocity is 0 and any re-compression
  // is over, as for reset(), but the margin grip keeps its grasp (GripLaw::pause): a stall is not
  // a new grasp, and a grip that started again from grip_min_n would open on the held object.
  void stop_for_stale() noexcept;

  const std::array<Vec3, kFingertips>& velocity() const { return velocity_; }
  const GripLaw& grip_law() const { return grip_; }
  // The paper's grip: always; the margin grip: once it has reached its target (GripLaw::reached).
  bool grip_ready() const noexcept { return !margin_ || grip_.reached(); }

 private:
  double approach_speed_;
  double recompress_gain_;
  double recompress_duration_;
  double recompress_limit_n_;  // recompress_max_f2_fraction * F2
  double backoff_speed_;
  double max_speed_;
  bool margin_;  // grip: margin
  GripLaw grip_;

  FingerMode mode_ = FingerMode::kOff;
  std::array<Vec3, kFingertips> velocity_{};
  std::array<FingerAction, kFingertips> action_{};
  std::array<bool, kFingertips> touched_{};
  std::array<double, kFingertips> recompress_until_{};
  std::array<bool, kFingertips> over_{};  // OVER in the previous update, for its rising edge

  // Velocity 0, no re-compression (reset and stop_for_stale).
  void stop() noexcept;
  // The margin grip's MOVE for fingertip f: the servo's squeeze; a raise on slip re-compresses.
  FingerAction margin_move(std::size_t f, const GripOutput& g, double now_s, Vec3& v) noexcept;
};

// The velocity scaled down, if needed, to at most max_speed in magnitude; 0 when not finite.
Vec3 bound_velocity(Vec3 v, double max_speed) noexcept;

}  // namespace tactile::control
