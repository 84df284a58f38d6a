// extraction_accuracy: centroid accuracy of every method against truth and the Cramer-Rao bound,
// and slip statistics, on synthetic frames (docs/benchmarks.md, "Extraction").
//
//   extraction_accuracy [--out DIR] [--frames N] [--slip-frames N] [--trials N] [--quick]
//
// Writes DIR/accuracy.csv, DIR/false_slips.csv and DIR/slip_delay.csv. Deterministic for a seed.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "harness.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"

namespace tactile::bench {
namespace {

using testing::SpotShape;

struct Plan {
  SpotSetting setting;
  int frames;
};

// The conditions of the issue: spot sigma 1 to 5 px, peak-to-noise 10 to 200, Gaussian,
// elliptical and flat-topped spots, 8 and 16 bits, Gaussian and shot noise. The target grid
// (Gaussian spots of sigma 1.5 to 4 px at peak-to-noise 25 to 150) gets the most frames: its
// bias must be resolved to a few 1e-4 px.
std::vector<Plan> plan(int frames) {
  std::vector<Plan> p;
  const int few = std::max(50, frames / 4);
  const auto add = [&](SpotShape shape, double sigma, double pnr, int depth, bool shot, int n) {
    SpotSetting s;
    s.shape = shape;
    s.sigma = sigma;
    s.pnr = pnr;
    s.depth = depth;
    s.shot_noise = shot;
    p.push_back({s, n});
  };
  for (double sigma : {1.5, 2.0, 2.5, 3.0, 4.0})
    for (double pnr : {25.0, 50.0, 100.0, 150.0})
      add(SpotShape::kGaussian, sigma, pnr, 8, false, frames);
  for (double sigma : {1.0, 5.0})
    for (double pnr : {10.0, 25.0, 50.0, 100.0, 150.0, 200.0})
      add(SpotShape::kGaussian, sigma, pnr, 8, false, few);
  for (double sigma : {1.5, 2.5, 4.0})
    for (double pnr : {10.0, 200.0})
      add(SpotShape::kGaussian, sigma, pnr, 8, false, few);
  for (SpotShape shape : {SpotShape::kElliptical, SpotShape::kFlatTop})
    for (double sigma : {1.0, 1.5, 2.5, 4.0, 5.0})
      for (double pnr : {10.0, 25.0, 50.0, 100.0, 200.0})
        add(shape, sigma, pnr, 8, false, few);
  for (double sigma : {1.5, 2.5, 4.0})
    for (double pnr : {10.0, 25.0, 50.0, 100.0, 200.0})
      add(SpotShape::kGaussian, sigma, pnr, 16, false, few);
  for (SpotShape shape : {SpotShape::kGaussian, SpotShape::kFlatTop})
    for (double sigma : {1.5, 2.5, 4.0})
      for (double pnr : {25.0, 50.0, 100.0, 200.0})
        add(shape, sigma, pnr, 8, true, few);
  return p;
}

// Issue 38's grid: Gaussian, elliptical (aspect 1.5 and 2), flat-topped and feeler spots at
// peak-to-noise 25 to 150, 8-bit, the spot sizes of the target grid.
std::vector<Plan> shape_grid(int frames) {
  std::vector<Plan> p;
  const auto add = [&](SpotShape shape, double sigma, double aspect, double pnr) {
    SpotSetting s;
    s.shape = shape;
    s.sigma = sigma;
    s.aspect = aspect;
    s.pnr = pnr;
    p.push_back({s, frames});
  };
  for (double pnr : {25.0, 50.0, 100.0, 150.0}) {
    for (double sigma : {1.5, 2.5, 4.0}) {
      add(SpotShape::kGaussian, sigma, 1.5, pnr);
      add(SpotShape::kElliptical, sigma, 2.0, pnr);
      add(SpotShape::kFlatTop, sigma, 1.5, pnr);
    }
    for (double sigma : {1.5, 2.5})
      add(SpotShape::kElliptical, sigma * 2 / 3, 1.5, pnr);
  }
  // The rig's feeler element (sigma unused; the contacts' level is the peak), after the others so
  // that theirs keep their seeds.
  for (double pnr : {25.0, 50.0, 100.0, 150.0})
    add(SpotShape::kFeelers, 0.0, 1.0, pnr);
  return p;
}

std::string num(double v, int digits = 6) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

int run(int argc, char** argv) {
  CLI::App app{"Centroid accuracy and slip statistics of the extraction methods"};
  std::string out = "out/bench";
  int frames = 1000;
  int slip_frames = 5000;
  int trials = 20000;
  bool quick = false;
  std::uint64_t seed = 1;
  app.add_option("--out", out, "output directory")->capture_default_str();
  app.add_option("--frames", frames, "frames per target accuracy setting (others: a quarter)")
      ->capture_default_str()
      ->check(CLI::Range(10, 1000000));
  app.add_option("--slip-frames", slip_frames, "still-contact frames at noise 2 (others: a fifth)")
      ->capture_default_str()
      ->check(CLI::Range(10, 10000000));
  app.add_option("--trials", trials, "slip-onset trials per speed")
      ->capture_default_str()
      ->check(CLI::Range(41, 10000000));
  app.add_option("--seed", seed, "random seed")->capture_default_str();
  app.add_flag("--quick", quick, "a short run (frames 120, slip frames 600, trials 2000)");
  bool target_grid_only = false;
  app.add_flag("--target-grid-only", target_grid_only,
               "only the Gaussian target grid (sigma 1.5-4 px, peak-to-noise 25-150, 8-bit)");
  bool shapes_only = false;
  app.add_flag(
      "--shape-grid-only", shapes_only,
      "only issue 38's grid: Gaussian, elliptical (aspect 1.5, 2), flat-topped and feeler spots, "
      "peak-to-noise 25-150, 8-bit, all with --frames frames");
  std::string only_methods;
  app.add_option("--methods", only_methods,
                 "comma-separated methods to measure (default: all; names as in the CSV)");
  bool no_accuracy = false;
  bool no_slips = false;
  app.add_flag("--no-accuracy", no_accuracy, "skip the accuracy grid");
  app.add_flag("--no-slips", no_slips, "skip the slip statistics");
  return cli::run(app, argc, argv, [&] {
    if (quick) {
      frames = 120;
      slip_frames = 600;
      trials = 2000;
    }
    const std::filesystem::path dir(out);
    std::vector<Method> all = methods();
    if (!only_methods.empty()) {
      std::vector<Method> chosen;
      std::stringstream names(only_methods);
      for (std::string name; std::getline(names, name, ',');) {
        const Method* m = find_method(name);
        if (m == nullptr) throw cli::UsageError("--methods: no method '" + name + "'");
        chosen.push_back(*m);
      }
      all = chosen;
    }

    if (!no_accuracy) {
      std::ostringstream acc;
      acc << "method,shape,sigma_px,pnr,depth,shot_noise,peak,noise_sigma,frames,samples,misses,"
             "rms_x_px,rms_y_px,rms_px,bias_px,bias_se_px,crb_x_px,crb_y_px,crb_simple_px,"
             "ratio_crb\n";
      std::vector<Plan> p = plan(frames);
      if (target_grid_only) p.resize(20);  // plan() lists the target grid first
      if (shapes_only) p = shape_grid(frames);
      for (std::size_t i = 0; i < p.size(); ++i) {
        const SpotSetting& s = p[i].setting;
        std::fprintf(stderr, "accuracy %zu/%zu: %s sigma %.1f pnr %.0f %d-bit%s, %d frames\n",
                     i + 1, p.size(), s.shape_name().c_str(), s.sigma, s.pnr, s.depth,
                     s.shot_noise ? " shot" : "", p[i].frames);
        for (const AccuracyRow& r : run_accuracy(s, all, p[i].frames, seed + i)) {
          acc << r.method << ',' << s.shape_name() << ',' << num(s.sigma) << ',' << num(s.pnr)
              << ',' << s.depth << ',' << (s.shot_noise ? 1 : 0) << ',' << num(s.peak()) << ','
              << num(s.noise_sigma()) << ',' << r.frames << ',' << r.samples << ',' << r.misses
              << ',' << num(r.rms_x) << ',' << num(r.rms_y) << ',' << num(r.rms()) << ','
              << num(r.bias) << ',' << num(r.bias_se) << ',' << num(r.crb.x) << ',' << num(r.crb.y)
              << ',' << num(r.crb_simple) << ',' << num(r.ratio()) << '\n';
        }
      }
      util::write_file_atomic(dir / "accuracy.csv", acc.str());
    }
    if (no_slips) return 0;

    std::ostringstream fs;
    fs << "method,noise_sigma,peak,element_frames,false_slips,rate,centroid_sigma_px,"
          "predicted_rate\n";
    struct Still {
      double noise;
      double peak;
      int frames;
    };
    std::vector<Still> still;
    for (double noise : {0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0})
      still.push_back({noise, 100, noise == 2.0 ? slip_frames : std::max(50, slip_frames / 5)});
    for (double peak : {30.0, 50.0, 200.0})
      still.push_back({2.0, peak, std::max(50, slip_frames / 5)});
    for (std::size_t i = 0; i < still.size(); ++i) {
      std::fprintf(stderr, "still contact: noise %.1f peak %.0f, %d frames\n", still[i].noise,
                   still[i].peak, still[i].frames);
      for (const FalseSlipRow& r :
           run_false_slips(all, still[i].noise, still[i].peak, still[i].frames, seed + 1000 + i)) {
        fs << r.method << ',' << num(r.noise_sigma) << ',' << num(r.peak) << ',' << r.element_frames
           << ',' << r.false_slips << ',' << num(r.rate()) << ',' << num(r.centroid_sigma_px) << ','
           << num(r.predicted) << '\n';
      }
    }
    util::write_file_atomic(dir / "false_slips.csv", fs.str());

    std::ostringstream ds;
    ds << "method,speed_dr,trials,within_1,within_2,undetected,early,p50,p99,max\n";
    for (double speed : {1.5, 3.0, 10.0}) {
      std::fprintf(stderr, "slip onset: %.1f dr per frame, %d trials\n", speed, trials);
      for (const DelayRow& r :
           run_delays(all, speed, trials, seed + 2000 + static_cast<int>(speed))) {
        ds << r.method << ',' << num(r.speed_dr) << ',' << r.trials << ',' << r.within_1 << ','
           << r.within_2 << ',' << r.undetected << ',' << r.early << ',' << num(r.p50) << ','
           << num(r.p99) << ',' << num(r.max) << '\n';
      }
    }
    util::write_file_atomic(dir / "slip_delay.csv", ds.str());
    std::fprintf(stderr, "wrote the CSV files in %s\n", out.c_str());
    return 0;
  });
}

}  // namespace
}  // namespace tactile::bench

int main(int argc, char** argv) {
  tactile::util::set_program_name("extraction_accuracy");
  return tactile::bench::run(argc, argv);
}
