#pragma once

// Plots of a lockstep run (docs/rig.md, "Plots"), PNG through tactile::plot:
//   fig10.png           the paper's Fig. 10: y-directional centroid change against the
//                       x-directional fingertip position over the whole task;
//   shear-<n>-<label>.png  Fig. 3 style shear vector fields of both fingertips at the moments
//                       the controller classified the grasp and the release, re-compressed in
//                       transport and found the cap tight;
//   timeline.png        flags, forces, cap angle and events against time.
#include <filesystem>
#include <vector>

#include "tactile/rig/lockstep.hpp"

namespace tactile::rig {

// Writes the plots into `dir` (created when missing) and returns the files written.
std::vector<std::filesystem::path> write_plots(const LockstepResult& run,
                                               const std::filesystem::path& dir);

}  // namespace tactile::rig
