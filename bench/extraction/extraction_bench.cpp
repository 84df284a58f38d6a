// Time per frame of every extraction method on the paper's sensor: 640 x 480, 41 elements of
// radius 14 px, Gaussian spots of sigma 2.5 px and peak 100 gray levels over a vignetted
// background with pixel noise 2 (peak-to-noise 50), with 0, 5, 20 and 41 elements in contact.
// Every method measures the same frames in the same process; run with repetitions and random
// interleaving (scripts/run-benchmarks) and compare medians.
//
//   extraction_bench [--depth 8|16] [google benchmark flags]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>

#include "baselines.hpp"
#include "scene.hpp"
#include "synthetic.hpp"

namespace tactile::bench {
namespace {

constexpr int kFrames = 16;  // rotating frames, so that nothing is faster for being cached

struct Scene {
  testing::SceneOptions options;
  Calibration cal;
  std::vector<Image> reference;
  std::vector<Image> frames;
};

// One scene per (depth, floor sigmas, contacts), rendered once and shared by the methods.
const Scene& scene(int depth, double floor_sigmas, int contacts) {
  static std::map<std::tuple<int, double, int>, std::unique_ptr<Scene>> cache;
  auto& slot = cache[{depth, floor_sigmas, contacts}];
  if (slot) return *slot;
  slot = std::make_unique<Scene>();
  Scene& s = *slot;
  s.options.bit_depth = depth;
  s.options.noise_sigma = 2.0;
  s.cal = dome_calibration(s.options, 14.0, floor_sigmas);
  util::Random rng(20240611 + static_cast<std::uint64_t>(contacts));
  const testing::SceneRenderer renderer(s.options, &s.cal);
  s.reference.resize(16);
  for (Image& f : s.reference)
    renderer.render({}, rng, f);
  const std::vector<std::size_t> order = press_order(s.cal.elements.size());
  s.frames.resize(kFrames);
  for (Image& f : s.frames) {
    std::vector<testing::Spot> spots;
    for (int k = 0; k < contacts; ++k) {
      const ElementCalibration& e = s.cal.elements[order[static_cast<std::size_t>(k)]];
      testing::Spot spot;
      spot.center = e.center_px + Vec2{rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5)};
      spot.peak = 100;
      spot.sigma = 2.5;
      spots.push_back(spot);
    }
    renderer.render(spots, rng, f);
  }
  return s;
}

void run_core(benchmark::State& state, const Method& m, int depth, int contacts) {
  const Scene& s = scene(depth, m.floor_sigmas, contacts);
  ExtractorOptions opt = options_for(m);
  opt.reference_frames = static_cast<int>(s.reference.size());
  Extractor ex(s.cal, opt);
  for (const Image& f : s.reference)
    ex.add_reference_frame(f.view());
  if (!ex.has_reference()) {
    state.SkipWithError("reference refused");
    return;
  }
  std::uint64_t seq = 0;
  for (auto _ : state) {
    const MeasureStatus st = ex.measure(s.frames[seq % kFrames].view(), {seq, 0});
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(ex.readings().data());
    ++seq;
  }
  int found = 0;
  for (const ElementReading& r : ex.readings())
    found += r.contact ? 1 : 0;
  state.counters["contacts"] = found;
}

void run_opencv(benchmark::State& state, const Method& m, int depth, int contacts) {
  const Scene& s = scene(depth, m.floor_sigmas, contacts);
  OpenCvBaseline base(s.cal);
  base.set_reference(s.reference);
  std::uint64_t seq = 0;
  for (auto _ : state) {
    base.measure(s.frames[seq % kFrames].view());
    benchmark::DoNotOptimize(base.results().data());
    ++seq;
  }
  int found = 0;
  for (const auto& r : base.results())
    found += r.contact ? 1 : 0;
  state.counters["contacts"] = found;
}

void run_floor(benchmark::State& state, const Method& m, int depth, int contacts) {
  const Scene& s = scene(depth, m.floor_sigmas, contacts);
  PixelSumFloor floor(s.cal);
  std::uint64_t seq = 0;
  for (auto _ : state) {
    floor.measure(s.frames[seq % kFrames].view());
    benchmark::DoNotOptimize(floor.sums().data());
    ++seq;
  }
  state.counters["contacts"] = contacts;
}

int run(int argc, char** argv) {
  int depth = 8;
  // Our own flag first; the rest goes to Google Benchmark.
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--depth") == 0 && i + 1 < argc) {
      depth = std::atoi(argv[++i]);
      continue;
    }
    args.push_back(argv[i]);
  }
  if (depth != 8 && depth != 16) {
    std::fprintf(stderr, "extraction_bench: --depth must be 8 or 16\n");
    return 2;
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 2;

  static const std::vector<Method> all = methods();
  for (const Method& m : all) {
    for (int contacts : {0, 5, 20, 41}) {
      const std::string name = "extract/" + m.name + "/mono" + std::to_string(depth) +
                               "/contacts:" + std::to_string(contacts);
      const Method* mp = &m;
      benchmark::RegisterBenchmark(name.c_str(),
                                   [mp, depth, contacts](benchmark::State& st) {
                                     switch (mp->kind) {
                                       case Method::Kind::kCore:
                                         run_core(st, *mp, depth, contacts);
                                         break;
                                       case Method::Kind::kOpenCv:
                                         run_opencv(st, *mp, depth, contacts);
                                         break;
                                       case Method::Kind::kFloor:
                                         run_floor(st, *mp, depth, contacts);
                                         break;
                                     }
                                   })
          ->Unit(benchmark::kMicrosecond)
          ->ComputeStatistics("min", [](const std::vector<double>& v) {
            return *std::min_element(v.begin(), v.end());
          });
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace
}  // namespace tactile::bench

int main(int argc, char** argv) {
  return tactile::bench::run(argc, argv);
}
