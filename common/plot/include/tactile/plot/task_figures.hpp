#pragma once

// The grasp-move-twist figures, drawn the same way wherever a run is plotted: the rig (lockstep
// and real time, rig/plots) and tactile_plot (a recording). One definition of each axis, one
// panel order, one set of event labels (docs/plot.md, "Task figures"):
//   fig10     the paper's Fig. 10: y-directional centroid change dy of the element moving most
//             against the x-directional fingertip position, i.e. the fingertip's position along
//             the transport (the horizontal direction from the cap's place to the bottle), with
//             the +-dr band;
//   timeline  panels flags, forces, centroid change, [cap angle], events against time, from
//             shortly before the first contact to the end.
// Both choose their y ranges from the data that matters (the bulk and the thresholds); slips
// beyond it are markers on the edge with their count.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tactile/plot/figure.hpp"

namespace tactile::plot {

// One fingertip over a run, one entry per camera frame (all vectors as long as t_s; the
// optional ones empty when unknown).
struct FingertipTrace {
  std::string name;
  std::vector<double> t_s;
  std::vector<double> x_mm;   // position along the transport (NaN where unknown)
  std::vector<double> dy_mm;  // y centroid change of the in-contact element moving most, mm/frame
  std::vector<double> max_fz_n;       // measured
  std::vector<double> max_fz_true_n;  // optional: the truth (rig)
  std::vector<std::uint8_t> touch, slip, over;
  std::vector<std::uint8_t> true_slip;  // optional: the truth (rig)
};

struct TaskEvent {
  double t_s = 0;
  std::string text;  // task_event_label()
};

struct TaskFigureInput {
  std::vector<FingertipTrace> fingertips;
  std::vector<TaskEvent> events;
  double f1_n = 0.5;
  double f2_n = 2.5;
  double dr_mm = 0.004;
  double twist_dr_factor = 1.3;
  std::string title;       // what was run; "" for none
  std::string x_source;    // where Fig. 10's x comes from, for its axis label ("" for none)
  bool x_is_time = false;  // no position known: x_mm holds the time (s) instead
  std::vector<double> cap_t_s, cap_angle_deg;  // optional: the true cap angle (rig)
};

// The label an event gets on the task figures from its kind's name as control::to_string and
// the wire's EventKind spell it (GRASP_CLASSIFIED, ...), and its twist cycle; nullopt for the
// kinds not marked (PHASE, TOUCH, OVER, STALE_HOLD, RESUMED).
std::optional<std::string> task_event_label(std::string_view kind, std::uint32_t cycle);

// The time window of the task figures: from shortly before the first TOUCH of any fingertip
// (5 % of the rest of the run, at least 0.5 s) to the last frame; the whole run without one.
std::optional<std::pair<double, double>> task_window(const TaskFigureInput& in);

Figure fig10(const TaskFigureInput& in, int width_px = 1000, int height_px = 600);
Figure timeline(const TaskFigureInput& in, int width_px = 1400, int height_px = 900);

}  // namespace tactile::plot
