#include "tactile/plot/task_figures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

namespace tactile::plot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fixed(double v, int decimals) {
  std::array<char, 32> buf{};
  std::snprintf(buf.data(), buf.size(), "%.*f", decimals, v);
  return buf.data();
}

bool inside(double t, const std::pair<double, double>& w) {
  return t >= w.first && t <= w.second;
}

// The centroid-change axis: the bulk of dy within the window (1 % and 99 % quantiles with a
// margin) and at least +-3 dr, so the dr band is a band; slips beyond are outlier markers.
std::pair<double, double> dy_range(const TaskFigureInput& in, const std::pair<double, double>& w) {
  std::vector<double> dy;
  for (const FingertipTrace& f : in.fingertips) {
    for (std::size_t i = 0; i < f.t_s.size(); ++i)
      if (inside(f.t_s[i], w)) dy.push_back(f.dy_mm[i]);
  }
  const double min_half = 3 * in.dr_mm;
  const auto r = robust_range(dy, RobustRange{0.01, 0.99, 0.15});
  double lo = std::min(r ? r->first : 0.0, -min_half);
  double hi = std::max(r ? r->second : 0.0, min_half);
  if (!(lo < hi)) {
    lo = -1;
    hi = 1;
  }
  return {lo, hi};
}

std::string dr_text(const TaskFigureInput& in) {
  return "+-dr = " + fixed(in.dr_mm, 4) + " mm (x" + fixed(in.twist_dr_factor, 1) +
         " while twisting): SLIP beyond";
}

Style thin(std::optional<Color> c = std::nullopt, bool dashed = false) {
  Style s;
  s.line_width = 1;
  s.color = c;
  s.dashed = dashed;
  return s;
}

// The x of fingertip `f` at time t: its frame nearest in time with a known x.
double x_at(const FingertipTrace& f, double t) {
  double best = std::numeric_limits<double>::infinity();
  double x = kNaN;
  for (std::size_t i = 0; i < f.t_s.size(); ++i) {
    if (!std::isfinite(f.x_mm[i])) continue;
    const double d = std::abs(f.t_s[i] - t);
    if (d < best) {
      best = d;
      x = f.x_mm[i];
    }
  }
  return x;
}

}  // namespace

std::optional<std::string> task_event_label(std::string_view kind, std::uint32_t cycle) {
  if (kind == "GRASPING_ENDED") return "grasped";
  if (kind == "GRASP_CLASSIFIED") return "grasp";
  if (kind == "RELEASE_CLASSIFIED") return "release";
  if (kind == "RECOMPRESS") return "re-compress";
  if (kind == "TWIST_CYCLE") return "cycle " + std::to_string(cycle);
  if (kind == "CAP_TIGHT") return "tight (" + std::to_string(cycle) + ")";
  if (kind == "DONE") return "done";
  if (kind == "ABORTED") return "aborted";
  return std::nullopt;
}

std::optional<std::pair<double, double>> task_window(const TaskFigureInput& in) {
  double first_touch = std::numeric_limits<double>::infinity();
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (const FingertipTrace& f : in.fingertips) {
    for (std::size_t i = 0; i < f.t_s.size(); ++i) {
      if (!std::isfinite(f.t_s[i])) continue;
      lo = std::min(lo, f.t_s[i]);
      hi = std::max(hi, f.t_s[i]);
      if (i < f.touch.size() && f.touch[i] != 0) first_touch = std::min(first_touch, f.t_s[i]);
    }
  }
  if (!(lo <= hi)) return std::nullopt;
  if (std::isfinite(first_touch))
    lo = std::max(lo, first_touch - std::max(0.5, 0.05 * (hi - first_touch)));
  if (!(lo < hi)) hi = lo + 1;
  return std::pair{lo, hi};
}

Figure fig10(const TaskFigureInput& in, int width_px, int height_px) {
  Figure fig(width_px, height_px);
  fig.title("Fig. 10: y-directional centroid change vs x-directional fingertip position" +
            (in.title.empty() ? std::string() : " (" + in.title + ")"));
  Panel& p = fig.add_panel();
  p.x_label(in.x_is_time ? std::string("time [s] (no fingertip position in the log)")
                         : "fingertip position along the transport, cap's place to bottle [mm]" +
                               (in.x_source.empty() ? std::string() : " (" + in.x_source + ")"))
      .y_label("dy_G [mm/frame] (+ along gravity)");
  const auto w = task_window(in);
  if (!w) return fig;
  const auto [lo, hi] = dy_range(in, *w);
  p.y_range(lo, hi).outlier_markers();
  p.band(-in.dr_mm, in.dr_mm, dr_text(in));
  for (const FingertipTrace& f : in.fingertips) {
    std::vector<double> x;
    std::vector<double> y;
    for (std::size_t i = 0; i < f.t_s.size(); ++i) {
      if (!inside(f.t_s[i], *w)) continue;
      x.push_back(f.x_mm[i]);
      y.push_back(f.dy_mm[i]);
    }
    p.line(x, y, f.name, thin());
  }
  // The moments the paper's Fig. 10 tells: the grasp and release classifications and the
  // re-compressions in transport, where the first fingertip was.
  if (!in.fingertips.empty()) {
    for (const TaskEvent& e : in.events) {
      if (e.text != "grasp" && e.text != "release" && e.text != "re-compress") continue;
      const double x = x_at(in.fingertips[0], e.t_s);
      if (std::isfinite(x)) p.vline(x, e.text, thin(kGray, true));
    }
  }
  return fig;
}

Figure timeline(const TaskFigureInput& in, int width_px, int height_px) {
  Figure fig(width_px, height_px);
  fig.title("Timeline: flags, forces, centroid change and events" +
            (in.title.empty() ? std::string() : " (" + in.title + ")"));
  fig.share_x();
  Panel& flags = fig.add_panel(0.9);
  Panel& forces = fig.add_panel(1.1);
  Panel& centroid = fig.add_panel(1.1);
  Panel* cap = in.cap_t_s.empty() ? nullptr : &fig.add_panel(0.7);
  Panel& events = fig.add_panel(0.55);
  const auto w = task_window(in);
  if (!w) return fig;
  flags.x_range(w->first, w->second);

  // Flags: one row each, either fingertip; the row's name at its right end.
  const bool truth = std::any_of(in.fingertips.begin(), in.fingertips.end(),
                                 [](const FingertipTrace& f) { return !f.true_slip.empty(); });
  struct Row {
    const char* name;
    std::vector<std::uint8_t> FingertipTrace::*flag;
  };
  std::vector<Row> rows{{"TOUCH", &FingertipTrace::touch},
                        {"SLIP", &FingertipTrace::slip},
                        {"OVER", &FingertipTrace::over}};
  if (truth) rows.push_back({"true slide", &FingertipTrace::true_slip});
  flags.y_label("flags (either)").no_legend().grid(false);
  flags.y_range(-0.3, 1.5 * static_cast<double>(rows.size()) - 0.2);
  for (std::size_t j = 0; j < rows.size(); ++j) {
    std::vector<double> t;
    std::vector<double> v;
    if (!in.fingertips.empty()) {
      const FingertipTrace& f0 = in.fingertips[0];
      for (std::size_t i = 0; i < f0.t_s.size(); ++i) {
        bool on = false;
        for (const FingertipTrace& f : in.fingertips) {
          const auto& flag = f.*rows[j].flag;
          on = on || (i < flag.size() && flag[i] != 0);
        }
        t.push_back(f0.t_s[i]);
        v.push_back(1.5 * static_cast<double>(j) + (on ? 1.0 : 0.0));
      }
    }
    const Color c = palette(j);
    flags.hline(1.5 * static_cast<double>(j), rows[j].name, thin(c));
    flags.step(t, v, {}, thin(c));
  }

  // Forces with F1 and F2.
  forces.y_label("max F_z [N]");
  for (std::size_t k = 0; k < in.fingertips.size(); ++k) {
    const FingertipTrace& f = in.fingertips[k];
    forces.line(f.t_s, f.max_fz_n, f.name + " measured", thin(palette(k)));
    if (!f.max_fz_true_n.empty()) {
      forces.line(f.t_s, f.max_fz_true_n, f.name + " true", thin(palette(k), true));
    }
  }
  forces.hline(in.f1_n, "F1 (TOUCH)", thin(kGray, true));
  forces.hline(in.f2_n, "F2 (OVER)", thin(kGray, true));

  // Centroid change with the dr band: the same axis as Fig. 10's y.
  const auto [lo, hi] = dy_range(in, *w);
  centroid.y_label("dy_G [mm/frame]").y_range(lo, hi).outlier_markers();
  centroid.band(-in.dr_mm, in.dr_mm, dr_text(in));
  for (std::size_t k = 0; k < in.fingertips.size(); ++k) {
    const FingertipTrace& f = in.fingertips[k];
    centroid.line(f.t_s, f.dy_mm, f.name, thin(palette(k)));
  }

  if (cap != nullptr) {
    cap->y_label("cap [deg]").line(in.cap_t_s, in.cap_angle_deg, "true cap angle", thin(kBlack));
  }

  // Events: a line through every panel, the label in the events panel (staggered downwards
  // where labels would overlap).
  events.y_range(0, 1).grid(false).no_legend().x_label("time [s]");
  events.y_label("events");
  for (const TaskEvent& e : in.events) {
    if (!inside(e.t_s, *w)) continue;
    for (std::size_t i = 0; i + 1 < fig.panel_count(); ++i)
      fig.panel(i).vline(e.t_s, {}, thin(Color{170, 170, 170}));
    events.vline(e.t_s, e.text, thin(Color{90, 90, 90}));
  }
  return fig;
}

}  // namespace tactile::plot
