#pragma once

// Synthetic sensors with known truth for tactile_calibrate's tests: the rig's simulated sensor
// (41 elements in rings of 1, 8, 16, 16, the rig's curves and normals; its optics render a
// spot whose measured G and centroid shift follow those curves), and known loads on it.
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/image.hpp"
#include "tactile/rig/optics.hpp"
#include "tactile/rig/world.hpp"
#include "tactile/util/random.hpp"

namespace tactile::testing::calib {

// The rig's element normals (World's dome: rings at polar 0, 10, 20, 30 degrees).
inline std::array<Vec3, rig::kElementsPerFingertip> rig_normals() {
  return rig::World(rig::WorldParams{}).element_normals();
}

inline constexpr double kRingPolarDeg[] = {0.0, 10.0, 20.0, 30.0};

class RigSensor {
 public:
  // What the pixels outside the disks show (rig::CameraParams): fresh noise from the model in
  // every frame, the rig cameras' live background, or the lockstep runner's first frame.
  enum class Outside { kFullNoise, kLive, kFrozen };
  explicit RigSensor(int bit_depth = 8, std::uint64_t seed = 7, double noise_sigma = 2.0,
                     Outside outside = Outside::kFullNoise)
      : cam_(camera(bit_depth, noise_sigma, outside)),
        truth_(rig::make_calibration("left", cam_, opt_, rig_normals())),
        renderer_(truth_, cam_, opt_, seed),
        rng_(seed + 1) {}

  const Calibration& truth() const { return truth_; }

  // One frame with these loads (element k of the calibration gets loads[k]). Rendered into the
  // same image every time, as the rig does (what the renderer leaves alone stays as it was).
  Image frame(std::span<const rig::ElementLoad> loads) {
    renderer_.render(loads, rng_, image_);
    return image_;
  }
  // Every element pressed with the same normal load, no shear.
  Image pressed(double fz_n) {
    std::vector<rig::ElementLoad> loads(truth_.elements.size(), rig::ElementLoad{fz_n, 0, 0});
    return frame(loads);
  }
  std::vector<Image> references(int n) {
    std::vector<Image> out;
    for (int i = 0; i < n; ++i)
      out.push_back(pressed(0.0));
    return out;
  }

 private:
  static rig::CameraParams camera(int bit_depth, double noise_sigma, Outside outside) {
    rig::CameraParams c;
    c.bit_depth = bit_depth;
    c.noise_sigma = noise_sigma;
    c.refresh_outside_disks = outside == Outside::kFullNoise;
    c.live_background = outside == Outside::kLive;
    return c;
  }

  rig::CameraParams cam_;
  rig::SensorOpticsParams opt_;
  Calibration truth_;
  rig::Renderer renderer_;
  util::Random rng_;
  Image image_;
};

// The signed shear displacement (mm) the rig's optics show for an applied shear force.
inline double shear_mm(const Calibration& c, double f_n) {
  const double u = c.shear_curve.inverse(std::abs(f_n));
  return f_n < 0 ? -u : u;
}

}  // namespace tactile::testing::calib
