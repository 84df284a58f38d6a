#include "tactile/rig/plots.hpp"

#include <algorithm>
#include <cctype>
#include <string>

#include "tactile/control/types.hpp"
#include "tactile/plot/figure.hpp"

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

bool key_event(std::uint8_t kind) {
  using control::EventKind;
  const auto k = static_cast<EventKind>(kind);
  return k == EventKind::kGraspingEnded || k == EventKind::kGraspClassified ||
         k == EventKind::kReleaseClassified || k == EventKind::kCapTight ||
         k == EventKind::kTwistCycle || k == EventKind::kDone || k == EventKind::kAborted;
}

std::string event_text(const EventRecord& e) {
  using control::EventKind;
  switch (static_cast<EventKind>(e.kind)) {
    case EventKind::kGraspingEnded:
      return "grasped";
    case EventKind::kGraspClassified:
      return "grasp";
    case EventKind::kReleaseClassified:
      return "release";
    case EventKind::kCapTight:
      return "tight (" + std::to_string(e.cycle) + ")";
    case EventKind::kTwistCycle:
      return "cycle " + std::to_string(e.cycle);
    case EventKind::kDone:
      return "done";
    case EventKind::kAborted:
      return "aborted";
    default:
      return e.kind_name;
  }
}

}  // namespace

std::vector<std::filesystem::path> write_plots(const LockstepResult& run,
                                               const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> written;
  const auto& frames = run.series.frames;
  const std::array<const char*, kFingertips> names{"left", "right"};

  // Fig. 10: y-directional centroid change against x-directional fingertip position.
  {
    plot::Figure fig(1000, 600);
    fig.title("Fig. 10: y-directional centroid change vs x-directional fingertip position");
    auto& p = fig.add_panel();
    p.x_label("fingertip position along the transport, cap to bottle [mm]")
        .y_label("dy_G [mm] (+ along gravity)");
    for (std::size_t i = 0; i < kFingertips; ++i) {
      std::vector<double> x;
      std::vector<double> y;
      for (const FrameSample& f : frames) {
        x.push_back(f.fingertip_x_m[i] * 1000.0);
        y.push_back(f.dy_mm[i]);
      }
      plot::Style s;
      s.line_width = 1;
      p.line(x, y, names[i], s);
    }
    // Solid thin lines: the plot library's dashes can stall on long segments (reported).
    plot::Style thin;
    thin.line_width = 1;
    thin.color = plot::kGray;
    p.hline(0.004, "dr", thin);
    p.hline(-0.004, "-dr", thin);
    written.push_back(dir / "fig10.png");
    fig.save_png(written.back());
  }

  // Fig. 3 style shear vector fields.
  int n = 0;
  for (const Snapshot& snap : run.series.snapshots) {
    plot::Figure fig(1100, 560);
    fig.title("Shear displacement u at t = " + std::to_string(snap.t).substr(0, 6) +
              " s: " + snap.label + " (arrows x40; red: SLIP)");
    for (std::size_t i = 0; i < kFingertips; ++i) {
      auto& p = fig.add_panel();
      p.title(std::string(names[i]) + " fingertip").equal_aspect().no_legend();
      p.x_label("image column [px]").y_label("-row [px]");
      const double mm_per_px = run.calibrations[i].mm_per_px;
      std::array<std::vector<double>, 2> x, y, dx, dy;
      for (const auto& e : snap.fingertips[i]) {
        plot::Style ring;
        ring.line_width = 1;
        ring.color = e.contact ? plot::Color{60, 60, 60} : plot::Color{200, 200, 200};
        p.circle(e.x_px, -e.y_px, run.calibrations[i].elements[0].radius_px, {}, ring);
        if (!e.contact) continue;
        const std::size_t g = e.slip ? 1 : 0;
        x[g].push_back(e.x_px);
        y[g].push_back(-e.y_px);
        dx[g].push_back(e.ux_mm / mm_per_px);
        dy[g].push_back(-e.uy_mm / mm_per_px);
      }
      for (std::size_t g = 0; g < 2; ++g) {
        plot::Style s;
        s.arrow_scale = 40;
        s.color = g == 1 ? plot::Color{214, 39, 40} : plot::Color{31, 119, 180};
        p.arrows(x[g], y[g], dx[g], dy[g], g == 1 ? "slip" : "stick", s);
      }
    }
    // Side by side would need columns; stacked panels keep both fingertips readable.
    written.push_back(dir / ("shear-" + std::to_string(++n) + "-" + slug(snap.label) + ".png"));
    fig.save_png(written.back());
  }

  // Timeline.
  {
    plot::Figure fig(1400, 900);
    fig.title("Timeline: forces, flags, cap and events").share_x();
    std::vector<double> t;
    for (const FrameSample& f : frames)
      t.push_back(f.t);
    auto& forces = fig.add_panel(1.3);
    forces.y_label("max F_z [N]");
    for (std::size_t i = 0; i < kFingertips; ++i) {
      std::vector<double> m;
      std::vector<double> tr;
      for (const FrameSample& f : frames) {
        m.push_back(f.max_fz_measured[i]);
        tr.push_back(f.max_fz_true[i]);
      }
      plot::Style s;
      s.line_width = 1;
      forces.line(t, m, std::string(names[i]) + " measured", s);
      forces.line(t, tr, std::string(names[i]) + " true", s);
    }
    auto& flags = fig.add_panel(1.2);
    flags.y_label("flags");
    const std::array<const char*, 4> flag_names{"TOUCH", "SLIP", "true slide", "OVER"};
    for (std::size_t j = 0; j < flag_names.size(); ++j) {
      std::vector<double> v;
      for (const FrameSample& f : frames) {
        bool on = false;
        for (std::size_t i = 0; i < kFingertips; ++i) {
          on = on || (j == 0   ? f.touch[i]
                      : j == 1 ? f.slip[i]
                      : j == 2 ? f.true_slip[i]
                               : f.over[i]);
        }
        v.push_back(static_cast<double>(j) * 1.5 + (on ? 1.0 : 0.0));
      }
      plot::Style s;
      s.line_width = 1;
      flags.step(t, v, flag_names[j], s);
    }
    auto& cap = fig.add_panel();
    cap.y_label("cap angle [deg]").x_label("simulated time [s]");
    std::vector<double> angle;
    for (const FrameSample& f : frames)
      angle.push_back(f.cap_angle_deg);
    cap.line(t, angle, "cap angle");
    for (const EventRecord& e : run.series.events) {
      if (!key_event(e.kind)) continue;
      plot::Style s;
      s.line_width = 1;
      s.color = plot::kGray;
      fig.mark(e.t, event_text(e), s);
    }
    written.push_back(dir / "timeline.png");
    fig.save_png(written.back());
  }
  return written;
}

}  // namespace tactile::rig
