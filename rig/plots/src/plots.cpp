#include "tactile/rig/plots.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "tactile/control/types.hpp"
#include "tactile/plot/figure.hpp"
#include "tactile/plot/task_figures.hpp"

namespace tactile::rig {
namespace {

std::string slug(const std::string& s) {
  std::string out;
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    out += std::isalnum(u) != 0 ? static_cast<char>(std::tolower(u)) : '-';
  }
  return out;
}

// The run as the task figures take it (the same figures tactile_plot draws from a recording).
plot::TaskFigureInput task_input(const LockstepResult& run, const control::Config& cfg) {
  const std::array<const char*, kFingertips> names{"left", "right"};
  plot::TaskFigureInput in;
  in.f1_n = cfg.f1_n;
  in.f2_n = cfg.f2_n;
  in.dr_mm = cfg.dr_mm;
  in.twist_dr_factor = cfg.twist_dr_factor;
  in.x_source = "the apex, simulated";
  for (std::size_t i = 0; i < kFingertips; ++i) {
    plot::FingertipTrace f;
    f.name = names[i];
    for (const FrameSample& s : run.series.frames) {
      f.t_s.push_back(s.t);
      f.x_mm.push_back(s.fingertip_x_m[i] * 1000.0);
      f.dy_mm.push_back(s.dy_mm[i]);
      f.max_fz_n.push_back(s.max_fz_measured[i]);
      f.max_fz_true_n.push_back(s.max_fz_true[i]);
      f.touch.push_back(s.touch[i] ? 1 : 0);
      f.slip.push_back(s.slip[i] ? 1 : 0);
      f.over.push_back(s.over[i] ? 1 : 0);
      f.true_slip.push_back(s.true_slip[i] ? 1 : 0);
    }
    in.fingertips.push_back(std::move(f));
  }
  for (const FrameSample& s : run.series.frames) {
    in.cap_t_s.push_back(s.t);
    in.cap_angle_deg.push_back(s.cap_angle_deg);
  }
  for (const EventRecord& e : run.series.events) {
    if (auto text = plot::task_event_label(e.kind_name, e.cycle)) in.events.push_back({e.t, *text});
  }
  return in;
}

}  // namespace

plot::Figure shear_figure(const Snapshot& snap,
                          const std::array<Calibration, kFingertips>& calibrations) {
  const std::array<const char*, kFingertips> names{"left", "right"};
  // Portrait: the fingertips, each about as tall as wide, stacked (Figure has no columns).
  plot::Figure fig(640, 1100);
  fig.title("Shear u, t = " + std::to_string(snap.t).substr(0, 6) + " s: " + snap.label);
  for (std::size_t i = 0; i < kFingertips; ++i) {
    auto& p = fig.add_panel();
    p.title(std::string(names[i]) + " fingertip (arrows: u x40; red: SLIP)")
        .equal_aspect()
        .no_legend();
    p.x_label("image column [px]").y_label("-row [px]");
    const double mm_per_px = calibrations[i].mm_per_px;
    const double radius_px = calibrations[i].elements[0].radius_px;
    std::array<std::vector<double>, 2> x, y, dx, dy;
    double x_lo = std::numeric_limits<double>::infinity();
    double x_hi = -x_lo;
    double y_lo = x_lo;
    double y_hi = -x_lo;
    for (const auto& e : snap.fingertips[i]) {
      x_lo = std::min(x_lo, e.x_px);
      x_hi = std::max(x_hi, e.x_px);
      y_lo = std::min(y_lo, -e.y_px);
      y_hi = std::max(y_hi, -e.y_px);
      plot::Style ring;
      ring.line_width = 1;
      ring.color = e.contact ? plot::Color{60, 60, 60} : plot::Color{200, 200, 200};
      p.circle(e.x_px, -e.y_px, radius_px, {}, ring);
      if (!e.contact) continue;
      const std::size_t g = e.slip ? 1 : 0;
      x[g].push_back(e.x_px);
      y[g].push_back(-e.y_px);
      dx[g].push_back(e.ux_mm / mm_per_px);
      dy[g].push_back(-e.uy_mm / mm_per_px);
    }
    // The axes are the elements' layout with the disks and one radius around them: an arrow
    // that reaches beyond is cut at the edge rather than shrinking the fingertip into a corner.
    if (x_lo <= x_hi) {
      const double margin = 2 * radius_px;
      p.x_range(x_lo - margin, x_hi + margin).y_range(y_lo - margin, y_hi + margin);
    }
    for (std::size_t g = 0; g < 2; ++g) {
      plot::Style s;
      s.arrow_scale = 40;
      s.color = g == 1 ? plot::Color{214, 39, 40} : plot::Color{31, 119, 180};
      p.arrows(x[g], y[g], dx[g], dy[g], g == 1 ? "slip" : "stick", s);
    }
  }
  fig.fit_height_to_aspect(1600);
  return fig;
}

std::vector<std::filesystem::path> write_plots(const LockstepResult& run,
                                               const control::Config& controller,
                                               const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> written;
  const plot::TaskFigureInput in = task_input(run, controller);
  written.push_back(dir / "fig10.png");
  plot::fig10(in).save_png(written.back());

  // Fig. 3 style shear vector fields.
  int n = 0;
  for (const Snapshot& snap : run.series.snapshots) {
    written.push_back(dir / ("shear-" + std::to_string(++n) + "-" + slug(snap.label) + ".png"));
    shear_figure(snap, run.calibrations).save_png(written.back());
  }

  written.push_back(dir / "timeline.png");
  plot::timeline(in).save_png(written.back());
  return written;
}

}  // namespace tactile::rig

namespace tactile::rig {

plot::Figure latency_figure(std::span<const double> latency_ms) {
  plot::Figure fig(900, 420);
  fig.title("camera timestamp -> ArmCommand received by the arm controller, real time");
  auto& p = fig.add_panel();
  p.x_label("latency [ms]").y_label("answered frames");
  std::vector<double> sorted(latency_ms.begin(), latency_ms.end());
  std::sort(sorted.begin(), sorted.end());
  const auto rank = [&](double q) {
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
    return sorted[std::clamp<std::size_t>(k, 1, sorted.size()) - 1];
  };
  // The bulk: a pause of the machine tens of milliseconds long is counted at the edge.
  const plot::RobustRange bulk{0.0, 0.95, 0.5};
  p.histogram(latency_ms, 60, bulk, std::to_string(latency_ms.size()) + " answered frames");
  if (!sorted.empty()) {
    plot::Style marker;
    marker.line_width = 1;
    marker.color = plot::Color{200, 40, 40};
    // A percentile beyond the bulk is named in the title, not drawn: its line would set the axis.
    const auto shown = plot::robust_range(latency_ms, bulk);
    const double shown_hi = shown ? shown->second : sorted.back();
    std::string beyond;
    char text[64];
    for (const double q : {0.5, 0.99}) {
      std::snprintf(text, sizeof text, "p%.0f %.2f ms", q * 100, rank(q));
      if (rank(q) <= shown_hi) {
        p.vline(rank(q), text, marker);
      } else {
        beyond += std::string(text) + ", ";
      }
    }
    std::snprintf(text, sizeof text, "max %.1f ms", sorted.back());
    p.title(beyond + text);
  }
  return fig;
}

std::filesystem::path write_latency_plot(std::span<const double> latency_ms,
                                         const std::filesystem::path& dir) {
  const auto path = dir / "latency.png";
  latency_figure(latency_ms).save_png(path);
  return path;
}

}  // namespace tactile::rig
