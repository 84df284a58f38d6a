// The sweep's plot (sweep.png), drawn by the project's one plotting path, tactile::plot.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "tactile/plot/figure.hpp"
#include "tactile/rig/sweep.hpp"

namespace tactile::rig::sweep {
namespace {

std::vector<double> finite_values(const std::vector<const Row*>& rows, const char* column) {
  std::vector<double> v;
  for (const Row* r : rows) {
    const double x = r->number(column);
    if (std::isfinite(x)) v.push_back(x);
  }
  return v;
}

// Sorted values against their rank as a share of the scenarios (an empirical CDF).
void ecdf(plot::Panel& p, std::vector<double> v, const std::string& label, plot::Style style) {
  std::sort(v.begin(), v.end());
  std::vector<double> share(v.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    share[i] = (static_cast<double>(i) + 0.5) / static_cast<double>(v.size());
  p.line(share, v, label, style);
}

}  // namespace

void write_plot(const std::vector<Row>& rows, const SweepInfo& info,
                const std::filesystem::path& png) {
  std::map<std::string, std::vector<const Row*>> by_method;
  for (const Row& r : rows)
    by_method[r.at("method")].push_back(&r);

  plot::Figure fig(1000, 2600);
  fig.title(fmt::format("sweep: seed {}, {} of {} scenarios", info.seed,
                        by_method.empty() ? 0 : by_method.begin()->second.size(), info.scenarios));
  auto& slip = fig.add_panel(1.4);
  slip.title("element-frame slip, sorted over the scenarios (dashed: ideal sensor)")
      .x_label("share of scenarios")
      .y_label("precision / recall")
      .x_range(0, 1)
      .y_robust(plot::RobustRange{0.0, 1.0, 0.05});
  auto& tight = fig.add_panel();
  tight.title("tightness error: declared minus true cycle").x_label("cycles").y_label("scenarios");
  auto& tight_s = fig.add_panel();
  tight_s.title("tightness error: \"tight\" declared minus the cap meeting its stop")
      .x_label("seconds")
      .y_label("scenarios");
  auto& tight_deg = fig.add_panel();
  tight_deg.title("over-tightening: wrist turn from the cap meeting its stop to \"tight\"")
      .x_label("degrees")
      .y_label("scenarios");
  auto& outcome = fig.add_panel();
  outcome.title("outcomes (rig failed: its process exited non-zero; time limit: max_time)")
      .y_label("scenarios");
  auto& force = fig.add_panel();
  force.title("peak grip force (largest element F_z)").x_label("F_z [N]").y_label("scenarios");
  auto& false_slips = fig.add_panel();
  false_slips.title("false slips (element-frames)").x_label("element-frames").y_label("scenarios");
  auto& grip = fig.add_panel();
  grip.title("grip over the least steady grip while held, sorted (solid: median, dashed: 95th pct)")
      .x_label("share of scenarios")
      .y_label("ratio")
      .x_range(0, 1)
      .y_robust(plot::RobustRange{0.0, 1.0, 0.1});
  auto& slide = fig.add_panel();
  slide.title("the cap's slide in the fingers while held").x_label("mm").y_label("scenarios");

  std::size_t m = 0;
  for (const auto& [method, mine] : by_method) {
    const std::size_t c = 2 * m;
    const plot::Style solid{plot::palette(c), 2, 4, false, 1};
    const plot::Style solid2{plot::palette(c + 1), 2, 4, false, 1};
    ecdf(slip, finite_values(mine, "precision"), method + " precision", solid);
    ecdf(slip, finite_values(mine, "recall"), method + " recall", solid2);
    ecdf(slip, finite_values(mine, "ideal_precision"), {}, {plot::palette(c), 1, 4, true, 1});
    ecdf(slip, finite_values(mine, "ideal_recall"), {}, {plot::palette(c + 1), 1, 4, true, 1});

    // Whole cycles: one bar per value.
    std::map<double, double> per_error;
    for (const double e : finite_values(mine, "tight_cycle_error"))
      per_error[e] += 1;
    std::vector<double> ex, ey;
    for (const auto& [e, k] : per_error) {
      ex.push_back(e + 0.3 * static_cast<double>(m));
      ey.push_back(k);
    }
    tight.bars(ex, ey, 0.3, method, solid);
    tight_s.histogram(finite_values(mine, "tight_time_error_s"), 30,
                      plot::RobustRange{0.0, 0.95, 0.1}, method, solid);
    tight_deg.histogram(finite_values(mine, "tight_error_deg"), 30,
                        plot::RobustRange{0.0, 0.95, 0.1}, method, solid);

    const auto count = [&](auto pred) {
      return static_cast<double>(std::count_if(mine.begin(), mine.end(), pred));
    };
    const std::vector<double> heights{
        count([](const Row* r) { return r->at("completed") == "true"; }),
        count([](const Row* r) { return r->at("end_reason").rfind("aborted", 0) == 0; }),
        count([](const Row* r) { return r->at("end_reason") == "max_time"; }),
        count([](const Row* r) { return r->at("dropped") == "true"; }),
        count([](const Row* r) { return r->number("over_events") > 0; }),
        count([](const Row* r) { return r->at("exit_status") != "0"; })};
    std::vector<double> ox;
    for (std::size_t i = 0; i < heights.size(); ++i)
      ox.push_back(static_cast<double>(i) + 0.3 * static_cast<double>(m));
    outcome.bars(ox, heights, 0.3, method, solid);
    if (m == 0) {
      outcome.scatter(ox, heights, {}, {plot::kBlack, 1, 2, false, 1},
                      {"completed", "aborted", "time limit", "dropped", "OVER", "rig failed"});
    }

    force.histogram(finite_values(mine, "max_fz_N"), 30, plot::RobustRange{0.0, 0.95, 0.1}, method,
                    solid);
    false_slips.histogram(finite_values(mine, "false_slips"), 30, plot::RobustRange{0.0, 0.95, 0.1},
                          method, solid);
    ecdf(grip, finite_values(mine, "grip_ratio_p50"), method, solid);
    ecdf(grip, finite_values(mine, "grip_ratio_p95"), {}, {plot::palette(c), 1, 4, true, 1});
    slide.histogram(finite_values(mine, "cap_slide_carry_mm"), 30,
                    plot::RobustRange{0.0, 0.95, 0.1}, method, solid);
    ++m;
  }
  fig.save_png(png);
}

}  // namespace tactile::rig::sweep
