// plot_gallery: draws one example of each kind of figure tactile::plot is for, on made-up data,
// into a directory (docs/img holds the pictures docs/plot.md shows):
//
//   plot_gallery OUT_DIR
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/plot/figure.hpp"

namespace {

using tactile::plot::Figure;
using tactile::plot::Scale;
using tactile::plot::Style;

void pareto(const std::filesystem::path& dir) {
  Figure fig(760, 480);
  auto& p = fig.add_panel();
  p.title("Run time against error (made-up figures)")
      .x_label("time per frame [us]")
      .y_label("RMS error [px]")
      .x_scale(Scale::kLog)
      .y_scale(Scale::kLog);
  const std::vector<double> t{12, 9, 15, 60, 110, 6};
  const std::vector<double> e{0.012, 0.016, 0.011, 0.045, 0.03, 0.09};
  p.scatter(t, e, "estimators", {},
            {"gaussian", "windowed", "gaussian 4.5", "plain", "opencv", "thresholded"});
  const std::vector<double> ft{6, 9, 12};
  const std::vector<double> fe{0.09, 0.016, 0.012};
  Style front;
  front.dashed = true;
  p.step(ft, fe, "front", front);
  Style floor;
  floor.line_width = 1;
  floor.dashed = true;
  p.vline(3, "pixel-sum floor", floor);
  fig.save_png(dir / "plot_pareto.png");
}

void centroid_change(const std::filesystem::path& dir) {
  // Fig. 10 style: y-centroid change against fingertip x position.
  Figure fig(760, 420);
  auto& p = fig.add_panel();
  p.title("y-directional centroid change against fingertip x position")
      .x_label("fingertip x [mm]")
      .y_label("dy_G [mm]");
  std::vector<double> x;
  std::vector<double> y;
  for (int i = 0; i <= 300; ++i) {
    const double xi = 200 + i * 0.5;
    x.push_back(xi);
    double v = 0.0015 * std::sin(xi * 0.9);
    if (xi > 262 && xi < 266) v += 0.009;
    if (xi > 318 && xi < 322) v -= 0.012;
    y.push_back(v);
  }
  p.line(x, y, "element 20");
  Style thr;
  thr.dashed = true;
  thr.color = tactile::plot::Color{200, 40, 40};
  p.hline(0.004, "dr", thr).hline(-0.004, "-dr", thr);
  fig.save_png(dir / "plot_centroid_change.png");
}

void shear_field(const std::filesystem::path& dir) {
  // Fig. 3 style: shear displacement arrows at the element positions over the sensor outline.
  Figure fig(560, 560);
  auto& p = fig.add_panel();
  p.title("Centroid displacement per element").x_label("x [mm]").y_label("y [mm]").equal_aspect();
  std::vector<double> x, y, dx, dy;
  const auto ring = [&](double r, int n, double phase) {
    for (int i = 0; i < n; ++i) {
      const double a = phase + 2 * std::numbers::pi * i / n;
      x.push_back(r * std::cos(a));
      y.push_back(r * std::sin(a));
      // A rotation about a point near the edge, plus a push along +x.
      dx.push_back(0.004 - 0.002 * (y.back() - 1.0));
      dy.push_back(0.002 * (x.back() - 4.0));
    }
  };
  ring(0, 1, 0);
  ring(2.5, 8, 0);
  ring(5.0, 16, 0.1);
  ring(7.5, 16, 0.3);
  Style s;
  s.arrow_scale = 80;
  p.arrows(x, y, dx, dy, "u (x80)", s);
  Style outline;
  outline.color = tactile::plot::kGray;
  outline.line_width = 1;
  p.circle(0, 0, 8.5, "sensor", outline);
  fig.save_png(dir / "plot_shear_field.png");
}

void timeline(const std::filesystem::path& dir) {
  Figure fig(800, 560);
  fig.title("Grasp timeline").share_x();
  std::vector<double> t, touch, slip, fz, fx;
  for (int i = 0; i <= 400; ++i) {
    const double ti = i * 0.01;
    t.push_back(ti);
    touch.push_back(ti > 0.6 ? 1 : 0);
    slip.push_back((ti > 1.52 && ti < 1.6) || (ti > 2.9 && ti < 2.95) ? 1 : 0);
    fz.push_back(ti < 0.6 ? 0 : 1.2 * (1 - std::exp(-(ti - 0.6) * 4)));
    fx.push_back(ti < 0.6 ? 0 : 0.3 * std::sin(ti * 3) * (ti > 1.5 ? 1 : 0.3));
  }
  auto& flags = fig.add_panel(0.6);
  flags.y_label("flags").y_range(-0.2, 2.4);
  std::vector<double> slip_offset(slip.begin(), slip.end());
  for (double& v : slip_offset)
    v += 1.2;
  flags.step(t, touch, "TOUCH").step(t, slip_offset, "SLIP");
  auto& forces = fig.add_panel();
  forces.y_label("force [N]").line(t, fz, "F_z").line(t, fx, "F_x");
  auto& disp = fig.add_panel(0.6);
  std::vector<double> d(t.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    d[i] = slip[i] > 0 ? 0.006 : 0.001 * std::sin(static_cast<double>(i) * 0.7);
  disp.y_label("|d| [mm]").x_label("time [s]").line(t, d, "max |d|");
  Style event;
  event.line_width = 1;
  fig.mark(0.6, "grasping ended", event)
      .mark(1.52, "re-compress", event)
      .mark(2.9, "release", event);
  fig.save_png(dir / "plot_timeline.png");
}

void latency(const std::filesystem::path& dir) {
  Figure fig(640, 400);
  std::vector<double> v;
  std::uint64_t s = 7;
  for (int i = 0; i < 4000; ++i) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    const double u = static_cast<double>(s >> 11) * 0x1.0p-53;
    v.push_back(0.45 + 0.35 * -std::log(1 - u));
  }
  v.push_back(48.0);  // one pause of the machine: counted at the edge, not setting the axis
  auto& p = fig.add_panel();
  p.title("Latency, camera to arm command").x_label("latency [ms]").y_label("frames");
  p.histogram(v, 40, tactile::plot::RobustRange{0.0, 0.99, 0.25}, "4001 frames");
  Style marker;
  marker.line_width = 1;
  marker.color = tactile::plot::Color{200, 40, 40};
  p.vline(0.69, "median", marker).vline(2.0, "p99", marker);
  fig.save_png(dir / "plot_latency.png");
}

int run(int argc, char** argv) {
  const std::string_view usage =
      "usage: plot_gallery OUT_DIR\n"
      "Draws the example figures of docs/plot.md (pareto, centroid change, shear field, "
      "timeline, latency) as PNG files into OUT_DIR.\n";
  if (argc == 2 && (std::string_view(argv[1]) == "-h" || std::string_view(argv[1]) == "--help")) {
    std::fwrite(usage.data(), 1, usage.size(), stdout);
    return 0;
  }
  if (argc != 2 || argv[1][0] == '-') {
    if (argc == 2) std::fprintf(stderr, "plot_gallery: unknown option '%s'\n", argv[1]);
    std::fwrite(usage.data(), 1, usage.size(), stderr);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  pareto(dir);
  centroid_change(dir);
  shear_field(dir);
  timeline(dir);
  latency(dir);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plot_gallery: %s\n", e.what());
    return 1;
  }
}
