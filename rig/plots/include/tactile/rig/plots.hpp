#pragma once

// Plots of a lockstep run (docs/rig.md, "Plots"), PNG through tactile::plot:
//   fig10.png           the paper's Fig. 10: y-directional centroid change against the
//                       x-directional fingertip position (tactile::plot::fig10);
//   shear-<n>-<label>.png  Fig. 3 style shear vector fields of both fingertips at the moments
//                       the controller classified the grasp and the release, re-compressed in
//                       transport and found the cap tight;
//   timeline.png        flags, forces, centroid change, cap angle, events against time
//                       (tactile::plot::timeline);
//   latency.png         real-time runs: camera timestamp -> ArmCommand received.
#include <array>
#include <filesystem>
#include <span>
#include <vector>

#include "tactile/control/config.hpp"
#include "tactile/plot/figure.hpp"
#include "tactile/rig/lockstep.hpp"

namespace tactile::rig {

// Writes the plots into `dir` (created when missing) and returns the files written.
// `controller` gives the thresholds drawn (F1, F2, dr).
std::vector<std::filesystem::path> write_plots(const LockstepResult& run,
                                               const control::Config& controller,
                                               const std::filesystem::path& dir);

// A shear-<n>-<label>.png figure: both fingertips' elements at one moment, their shear
// displacement u as arrows (x40, red where the controller's detector said SLIP), each panel's
// axes the elements' layout with a margin, drawn to scale and filling its panel.
plot::Figure shear_figure(const Snapshot& snap,
                          const std::array<Calibration, kFingertips>& calibrations);

// The latency histogram: the bulk of the samples on the x axis (a machine's pause of tens of
// milliseconds counted at the edge), p50 and p99 drawn where they fall inside it and named in
// the title where they do not, the maximum in the title.
plot::Figure latency_figure(std::span<const double> latency_ms);
// latency.png: a histogram of the real-time run's camera timestamp -> ArmCommand received.
std::filesystem::path write_latency_plot(std::span<const double> latency_ms,
                                         const std::filesystem::path& dir);

}  // namespace tactile::rig
