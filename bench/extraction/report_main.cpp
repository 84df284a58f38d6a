// extraction_report: joins the timings of extraction_bench (Google Benchmark JSON) and the tables
// of extraction_accuracy into the Pareto table and plot and a Markdown summary with the target
// checks (docs/benchmarks.md, "Extraction").
//
//   extraction_report --in DIR [--out DIR]
//
// Reads DIR/extraction_times.json (and DIR/extraction_times_mono16.json when present),
// DIR/accuracy.csv, DIR/false_slips.csv, DIR/slip_delay.csv; writes pareto.csv, pareto.png and
// summary.md.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "scene.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/plot/figure.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"

namespace tactile::bench {
namespace {

namespace fs = std::filesystem;

// --- inputs -------------------------------------------------------------------------------------

using Row = std::map<std::string, std::string>;

std::vector<Row> read_csv(const fs::path& path) {
  std::istringstream in(util::read_file(path));
  std::string line;
  std::vector<std::string> header;
  std::vector<Row> rows;
  const auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::string cell;
    std::istringstream ss(s);
    while (std::getline(ss, cell, ','))
      out.push_back(cell);
    return out;
  };
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (header.empty()) {
      header = split(line);
      continue;
    }
    const auto cells = split(line);
    if (cells.size() != header.size()) {
      throw std::runtime_error(path.string() + ": a row has " + std::to_string(cells.size()) +
                               " cells, the header " + std::to_string(header.size()));
    }
    Row r;
    for (std::size_t i = 0; i < cells.size(); ++i)
      r[header[i]] = cells[i];
    rows.push_back(std::move(r));
  }
  return rows;
}

double num(const Row& r, const std::string& key) {
  const auto it = r.find(key);
  if (it == r.end()) throw std::runtime_error("missing column " + key);
  return std::stod(it->second);
}

// Median and minimum CPU time per frame (us) of "extract/<method>/mono<d>/contacts:<k>".
struct Timing {
  double median_us = NAN;
  double min_us = NAN;
  int repetitions = 0;
};
using Timings = std::map<std::string, Timing>;  // key "<method>/<contacts>"

// Google Benchmark writes NaN for some aggregates (the coefficient of variation of a constant
// counter), which JSON has not: read them as null.
std::string without_nan(std::string text) {
  for (const char* bad : {"-nan", "NaN", "nan", "-inf", "inf"}) {
    const std::string needle = std::string(": ") + bad;
    for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at))
      text.replace(at, needle.size(), ": null");
  }
  return text;
}

Timings read_times(const fs::path& path) {
  const nlohmann::json j = nlohmann::json::parse(without_nan(util::read_file(path)));
  Timings t;
  for (const auto& b : j.at("benchmarks")) {
    if (b.value("run_type", "") != "aggregate") continue;
    const std::string run = b.at("run_name").get<std::string>();
    const std::string agg = b.at("aggregate_name").get<std::string>();
    // extract/<method>/mono8/contacts:<k>
    const auto p1 = run.find('/');
    const auto p2 = run.find('/', p1 + 1);
    const auto p3 = run.rfind(':');
    if (p1 == std::string::npos || p2 == std::string::npos || p3 == std::string::npos) continue;
    const std::string key = run.substr(p1 + 1, p2 - p1 - 1) + "/" + run.substr(p3 + 1);
    double v = b.at("cpu_time").get<double>();
    const std::string unit = b.value("time_unit", "us");
    if (unit == "ns") v /= 1000;
    if (unit == "ms") v *= 1000;
    if (agg == "median") {
      t[key].median_us = v;
      t[key].repetitions = b.value("repetitions", 0);
    }
    if (agg == "min") t[key].min_us = v;
  }
  return t;
}

// --- formatting ---------------------------------------------------------------------------------

std::string fmt(double v, int digits = 3) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string pass(bool ok) {
  return ok ? "**met**" : "**not met**";
}

bool same(double a, double b) {
  return std::abs(a - b) < 1e-9;
}

// --- the report ---------------------------------------------------------------------------------

struct Point {
  std::string method;
  double time_us;
  double time_min_us;
  double rms;
  double ratio;
  bool front = false;
};

int report(const std::string& in, std::string out) {
  if (out.empty()) out = in;
  const fs::path din(in);
  const fs::path dout(out);

  const Timings times = read_times(din / "extraction_times.json");
  std::optional<Timings> times16;
  if (fs::exists(din / "extraction_times_mono16.json"))
    times16 = read_times(din / "extraction_times_mono16.json");
  const std::vector<Row> acc = read_csv(din / "accuracy.csv");
  const std::vector<Row> fsl = read_csv(din / "false_slips.csv");
  const std::vector<Row> dly = read_csv(din / "slip_delay.csv");
  const std::vector<Method> all = methods();
  const std::string def = all.front().name;

  const auto timing = [&](const std::string& m, int contacts) {
    const auto it = times.find(m + "/" + std::to_string(contacts));
    return it == times.end() ? Timing{} : it->second;
  };
  // The reference accuracy setting: the timing scene's spots.
  const auto ref_row = [&](const std::string& m) -> const Row* {
    for (const Row& r : acc) {
      if (r.at("method") == m && r.at("shape") == "gaussian" && same(num(r, "sigma_px"), 2.5) &&
          same(num(r, "pnr"), 50) && num(r, "depth") == 8 && num(r, "shot_noise") == 0)
        return &r;
    }
    return nullptr;
  };

  // Pareto points: every method with a centroid, time at 41 contacts against RMS error.
  std::vector<Point> pts;
  for (const Method& m : all) {
    if (m.kind == Method::Kind::kFloor) continue;
    const Row* r = ref_row(m.name);
    const Timing t = timing(m.name, 41);
    if (r == nullptr || !std::isfinite(t.median_us)) continue;
    pts.push_back({m.name, t.median_us, t.min_us, num(*r, "rms_px"), num(*r, "ratio_crb")});
  }
  for (Point& p : pts) {
    p.front = std::none_of(pts.begin(), pts.end(), [&](const Point& q) {
      return (q.time_us <= p.time_us && q.rms < p.rms) || (q.time_us < p.time_us && q.rms <= p.rms);
    });
  }
  std::ostringstream pc;
  pc << "method,time_us_median,time_us_min,rms_px,ratio_crb,pareto_front\n";
  for (const Point& p : pts) {
    pc << p.method << ',' << fmt(p.time_us, 4) << ',' << fmt(p.time_min_us, 4) << ','
       << fmt(p.rms, 4) << ',' << fmt(p.ratio, 3) << ',' << (p.front ? 1 : 0) << '\n';
  }
  util::write_file_atomic(dout / "pareto.csv", pc.str());

  // The plot.
  {
    plot::Figure fig(900, 560);
    auto& panel = fig.add_panel();
    panel.title("Extraction: time per frame against centroid error")
        .x_label("CPU time per frame, 640x480 Mono8, 41 elements in contact [us] (median)")
        .y_label("RMS centroid error [px], sigma 2.5 px, peak-to-noise 50")
        .x_scale(plot::Scale::kLog)
        .y_scale(plot::Scale::kLog)
        .legend(plot::Corner::kTopRight);
    std::vector<double> x, y;
    std::vector<std::string> labels;
    std::vector<Point> front;
    for (const Point& p : pts) {
      x.push_back(p.time_us);
      y.push_back(p.rms);
      labels.push_back(p.method);
      if (p.front) front.push_back(p);
    }
    panel.scatter(x, y, "estimators", {}, labels);
    std::sort(front.begin(), front.end(),
              [](const Point& a, const Point& b) { return a.time_us < b.time_us; });
    std::vector<double> fx, fy;
    for (const Point& p : front) {
      fx.push_back(p.time_us);
      fy.push_back(p.rms);
    }
    plot::Style dashed;
    dashed.dashed = true;
    panel.step(fx, fy, "Pareto front", dashed);
    const Row* r = ref_row(def);
    if (r != nullptr) {
      plot::Style bound;
      bound.color = plot::kGray;
      bound.line_width = 1;
      bound.dashed = true;
      panel.hline(num(*r, "crb_x_px"), "Cramer-Rao bound", bound);
    }
    const Timing fl = timing("floor", 41);
    if (std::isfinite(fl.median_us)) {
      plot::Style floor;
      floor.line_width = 1;
      floor.dashed = true;
      panel.vline(fl.median_us, "pixel-sum floor", floor);
      panel.vline(2 * fl.median_us, "2 x floor", floor);
    }
    fig.save_png(dout / "pareto.png");
  }

  // The summary.
  std::ostringstream md;
  md << "## Extraction: measured\n\n";
  md << "Timing: CPU time per frame, median of " << timing(def, 41).repetitions
     << " interleaved repetitions (minimum in brackets), 640x480 Mono8, 41 elements of radius "
        "14 px, Gaussian spots of sigma 2.5 px and peak 100 over pixel noise 2.\n\n";
  md << "| method | 0 contacts | 5 | 20 | 41 | 41: x faster than opencv | 41: x floor |\n";
  md << "|---|---|---|---|---|---|---|\n";
  const Timing cv41 = timing("opencv", 41);
  const Timing fl41 = timing("floor", 41);
  for (const Method& m : all) {
    md << "| " << m.name << (m.is_default ? " (default)" : "");
    for (int k : {0, 5, 20, 41}) {
      const Timing t = timing(m.name, k);
      md << " | " << fmt(t.median_us) << " (" << fmt(t.min_us) << ")";
    }
    const Timing t = timing(m.name, 41);
    md << " | " << fixed(cv41.median_us / t.median_us, 1) << " | "
       << fixed(t.median_us / fl41.median_us, 2) << " |\n";
  }
  if (times16) {
    md << "\nMono16, 41 contacts: ";
    for (const auto& [key, t] : *times16) {
      if (key.size() > 3 && key.substr(key.size() - 3) == "/41")
        md << key.substr(0, key.size() - 3) << " " << fmt(t.median_us) << " us; ";
    }
    md << "\n";
  }

  md << "\nPareto points (time at 41 contacts, error at sigma 2.5 px, peak-to-noise 50, "
        "8-bit):\n\n";
  md << "| method | time [us] | RMS [px] | x CRB | on the front |\n|---|---|---|---|---|\n";
  for (const Point& p : pts) {
    md << "| " << p.method << " | " << fmt(p.time_us) << " | " << fixed(p.rms, 4) << " | "
       << fixed(p.ratio, 2) << " | " << (p.front ? "yes" : "") << " |\n";
  }

  // Accuracy of every method over the target grid.
  const auto in_target = [](const Row& r) {
    const double s = num(r, "sigma_px");
    const double pnr = num(r, "pnr");
    return r.at("shape") == "gaussian" && num(r, "depth") == 8 && num(r, "shot_noise") == 0 &&
           s >= 1.5 && s <= 4 && pnr >= 25 && pnr <= 150;
  };
  md << "\nGaussian spots, sigma 1.5 to 4 px, peak-to-noise 25 to 150, 8-bit (the target grid): "
        "worst case per method.\n\n";
  md << "| method | worst RMS / CRB | at | worst bias [px] (std. error) | at | samples per "
        "setting |\n|---|---|---|---|---|---|\n";
  for (const Method& m : all) {
    if (m.kind == Method::Kind::kFloor) continue;
    double worst_ratio = 0, worst_bias = 0, bias_se = 0;
    std::string at_ratio, at_bias;
    std::int64_t samples = 0;
    for (const Row& r : acc) {
      if (r.at("method") != m.name || !in_target(r)) continue;
      const std::string where = "s " + r.at("sigma_px") + ", pnr " + r.at("pnr");
      if (num(r, "ratio_crb") > worst_ratio) {
        worst_ratio = num(r, "ratio_crb");
        at_ratio = where;
      }
      if (num(r, "bias_px") > worst_bias) {
        worst_bias = num(r, "bias_px");
        bias_se = num(r, "bias_se_px");
        at_bias = where;
      }
      samples = static_cast<std::int64_t>(num(r, "samples"));
    }
    md << "| " << m.name << " | " << fixed(worst_ratio, 2) << " | " << at_ratio << " | "
       << fixed(worst_bias, 4) << " (" << fixed(bias_se, 4) << ") | " << at_bias << " | " << samples
       << " |\n";
  }

  // The default over every condition.
  md << "\nDefault estimator (" << def << ") over every condition (RMS of the worse axis, "
     << "ratio to the Cramer-Rao bound of that axis, bias, missed contacts):\n\n";
  md << "| shape | sigma | pnr | bits | shot | RMS [px] | x CRB | CRB x/y [px] | bias [px] | "
        "missed |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : acc) {
    if (r.at("method") != def) continue;
    md << "| " << r.at("shape") << " | " << r.at("sigma_px") << " | " << r.at("pnr") << " | "
       << r.at("depth") << " | " << (r.at("shot_noise") == "1" ? "yes" : "") << " | "
       << fixed(num(r, "rms_px"), 4) << " | " << fixed(num(r, "ratio_crb"), 2) << " | "
       << fixed(num(r, "crb_x_px"), 4) << "/" << fixed(num(r, "crb_y_px"), 4) << " | "
       << fixed(num(r, "bias_px"), 4) << " | " << r.at("misses") << "/"
       << static_cast<std::int64_t>(num(r, "samples") + num(r, "misses")) << " |\n";
  }

  // Slips.
  md << "\nFalse slips on a still contact (41 elements, spots of sigma 2.5 px), per "
        "element-frame, against pixel noise and spot peak; predicted = exp(-dr^2 / (4 s^2)) "
        "from the measured centroid spread s:\n\n";
  md << "| method | noise | peak | element-frames | false slips | rate | centroid sigma [px] | "
        "predicted |\n|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : fsl) {
    md << "| " << r.at("method") << " | " << r.at("noise_sigma") << " | " << r.at("peak") << " | "
       << r.at("element_frames") << " | " << r.at("false_slips") << " | " << fmt(num(r, "rate"), 2)
       << " | " << fixed(num(r, "centroid_sigma_px"), 4) << " | "
       << fmt(num(r, "predicted_rate"), 2) << " |\n";
  }
  md << "\nSlip onset: spots that start moving at k dr per frame (dr = 0.004 mm = 0.16 px); delay "
        "1 = reported on the first frame that moved:\n\n";
  md << "| method | k | trials | within 1 frame | within 2 | p50 | p99 | max | never | before "
        "onset |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : dly) {
    const double n = num(r, "trials");
    md << "| " << r.at("method") << " | " << r.at("speed_dr") << " | " << r.at("trials") << " | "
       << fixed(100 * num(r, "within_1") / n, 2) << " % | "
       << fixed(100 * num(r, "within_2") / n, 2) << " % | " << r.at("p50") << " | " << r.at("p99")
       << " | " << r.at("max") << " | " << r.at("undetected") << " | " << r.at("early") << " |\n";
  }

  // Target checks.
  md << "\nTargets:\n\n";
  {
    double worst_ratio = 0, worst_bias = 0;
    for (const Row& r : acc) {
      if (r.at("method") != def || !in_target(r)) continue;
      worst_ratio = std::max(worst_ratio, num(r, "ratio_crb"));
      worst_bias = std::max(worst_bias, num(r, "bias_px"));
    }
    md << "- Default estimator on Gaussian spots (sigma 1.5-4, pnr 25-150): RMS at most 1.2 x CRB: "
       << pass(worst_ratio <= 1.2) << " (worst " << fixed(worst_ratio, 2)
       << "); bias at most 0.001 px: " << pass(worst_bias <= 0.001) << " (worst "
       << fixed(worst_bias, 4) << " px).\n";
    // Elliptical and flat-topped spots, each with read noise only (the target's condition) and
    // with shot noise; the Cramer-Rao bound says what any estimator could do there. Where the
    // target is missed at peak-to-noise 25, the same from 50.
    for (const std::string shape : {"elliptical", "flat-top"}) {
      for (const bool shot : {false, true}) {
        for (const double min_pnr : {25.0, 50.0}) {
          double worst = 0;
          double worst_crb = 0;
          std::string where;
          for (const Row& r : acc) {
            if (r.at("method") != def || r.at("shape") != shape || num(r, "pnr") < min_pnr ||
                (num(r, "shot_noise") != 0) != shot)
              continue;
            if (num(r, "rms_px") > worst) {
              worst = num(r, "rms_px");
              worst_crb = std::max(num(r, "crb_x_px"), num(r, "crb_y_px"));
              where = "sigma " + r.at("sigma_px") + " pnr " + r.at("pnr");
            }
          }
          if (where.empty()) continue;
          md << "- " << shape << " spots at pnr >= " << fmt(min_pnr)
             << (shot ? ", with shot noise" : ", read noise")
             << ": RMS at most 0.03 px: " << pass(worst <= 0.03) << " (worst " << fixed(worst, 4)
             << " px at " << where << "; Cramer-Rao bound there " << fixed(worst_crb, 4) << " px"
             << (worst_crb > 0.03 ? ", above the target: no estimator can meet it" : "") << ").\n";
          if (worst <= 0.03) break;
        }
      }
    }
    const Timing t = timing(def, 41);
    md << "- 41 contacts, Mono8: median at most 20 us: " << pass(t.median_us <= 20) << " ("
       << fmt(t.median_us)
       << " us); at least 5 x faster than opencv: " << pass(cv41.median_us / t.median_us >= 5)
       << " (" << fixed(cv41.median_us / t.median_us, 1)
       << " x); within 2 x of the floor: " << pass(t.median_us / fl41.median_us <= 2) << " ("
       << fixed(t.median_us / fl41.median_us, 2) << " x).\n";
    for (const Row& r : fsl) {
      if (r.at("method") == def && same(num(r, "noise_sigma"), 2) && same(num(r, "peak"), 100)) {
        md << "- Still contact at noise 2: at most 1e-4 false slips per element-frame: "
           << pass(num(r, "rate") <= 1e-4) << " (" << r.at("false_slips") << " in "
           << r.at("element_frames") << ").\n";
      }
    }
    for (const Row& r : dly) {
      if (r.at("method") == def && same(num(r, "speed_dr"), 1.5)) {
        const double share = num(r, "within_2") / num(r, "trials");
        md << "- Slips at 1.5 dr: detected within 2 frames in at least 99 % of trials: "
           << pass(share >= 0.99) << " (" << fixed(100 * share, 2) << " % of " << r.at("trials")
           << ").\n";
      }
    }
  }
  util::write_file_atomic(dout / "summary.md", md.str());
  std::fprintf(stderr, "wrote %s/{pareto.csv,pareto.png,summary.md}\n", out.c_str());
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"Pareto table, plot and summary of the extraction benchmarks"};
  std::string in = "out/bench";
  std::string out;
  app.add_option("--in", in, "directory with the benchmark outputs")->capture_default_str();
  app.add_option("--out", out, "output directory (default: --in)");
  return cli::run(app, argc, argv, [&] { return report(in, out); });
}

}  // namespace
}  // namespace tactile::bench

int main(int argc, char** argv) {
  tactile::util::set_program_name("extraction_report");
  return tactile::bench::run(argc, argv);
}
