// CPU time of one fingertip frame through each slip detector (docs/slip.md, "The detectors"), in
// the extraction benchmark's style: 41 elements of the paper's sensor, 0, 5, 20 and 41 of them in
// contact, 16 rotating frames of random displacements and loads, every method on the same frames
// in one process. The paper's rule is the baseline: compare the medians' ratio, run with
// repetitions and random interleaving:
//
//   slip_detector_bench --benchmark_repetitions=15 --benchmark_enable_random_interleaving=true
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "tactile/control/flag_analyzer.hpp"
#include "tactile/control/slip_detector.hpp"

namespace tactile::control {
namespace {

constexpr int kElements = 41;
constexpr int kFrames = 16;

struct Frames {
  std::array<std::array<ElementReading, kElements>, kFrames> frames{};
};

// Elements on the paper's layout (a disk of 41 on a 40 px grid), the first `contacts` in contact
// with loads up to the cone's edge and displacements around dr: every branch of the detectors
// is taken.
const Frames& frames(int contacts) {
  static std::array<Frames, kElements + 1> cache{};
  static std::array<bool, kElements + 1> made{};
  Frames& f = cache[static_cast<std::size_t>(contacts)];
  if (made[static_cast<std::size_t>(contacts)]) return f;
  made[static_cast<std::size_t>(contacts)] = true;
  std::mt19937_64 rng(20261126 + static_cast<std::uint64_t>(contacts));
  std::uniform_real_distribution<double> d(-0.008, 0.008), ratio(0.0, 0.9), fz(0.05, 1.5);
  for (auto& frame : f.frames) {
    for (int i = 0; i < kElements; ++i) {
      ElementReading& r = frame[static_cast<std::size_t>(i)];
      r.id = static_cast<std::uint32_t>(i);
      r.x_px = 320.0 + 40.0 * (i % 7 - 3);
      r.y_px = 240.0 + 40.0 * (i / 7 - 3);
      r.contact = i < contacts;
      r.has_displacement = r.contact;
      if (!r.contact) continue;
      r.fz = fz(rng);
      const double t = ratio(rng) * r.fz;
      r.fx = 0.6 * t;
      r.fy = 0.8 * t;
      r.dx_mm = d(rng);
      r.dy_mm = d(rng);
    }
  }
  return f;
}

void run(benchmark::State& state, SlipDetectorKind kind) {
  const Frames& f = frames(static_cast<int>(state.range(0)));
  Config cfg;
  SlipDetector det(kind, cfg);
  FlagAnalyzer flags(cfg);
  FingertipInput in;
  in.fresh = true;
  std::size_t n = 0;
  for (auto _ : state) {
    in.elements = f.frames[n++ % kFrames];
    in.camera_timestamp_ns = static_cast<std::int64_t>(n) * 5'000'000;  // 200 fps
    const FingertipSlip& s = det.update(0, in, 0.004, ArmMotion{0.0, 0.5});
    const FingertipFlags ff = flags.analyze(in, s);
    benchmark::DoNotOptimize(ff);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void paper(benchmark::State& s) {
  run(s, SlipDetectorKind::kPaper);
}
void field(benchmark::State& s) {
  run(s, SlipDetectorKind::kField);
}
void learned(benchmark::State& s) {
  run(s, SlipDetectorKind::kLearned);
}

BENCHMARK(paper)->ArgName("contacts")->Arg(0)->Arg(5)->Arg(20)->Arg(41);
BENCHMARK(field)->ArgName("contacts")->Arg(0)->Arg(5)->Arg(20)->Arg(41);
BENCHMARK(learned)->ArgName("contacts")->Arg(0)->Arg(5)->Arg(20)->Arg(41);

}  // namespace
}  // namespace tactile::control

// Google Benchmark's flags only; an unknown option is a usage error (exit 2), as for every program.
int main(int argc, char** argv) {
  using tactile::control::SlipDetector;
  // The model's size and the scoring path this processor takes ("avx2" or "portable").
  benchmark::AddCustomContext("slip_model",
                              std::to_string(SlipDetector::model().trees()) + " trees");
  benchmark::AddCustomContext("model_scoring", SlipDetector::model().vector_scoring());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
