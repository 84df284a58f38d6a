// Soak in lockstep (docs/reliability.md, "Soak"): the default scenario repeated for 30 simulated
// minutes in one process. Every repetition must give the same report as the first (nothing
// carries over from one run to the next), the process's memory must stay within a bound
// measured after the first runs, and the per-frame scores must add up to the totals.
// TACTILE_SOAK_SIM_S overrides the simulated time (s). Built with the sanitizers
// (TACTILE_SANITIZED): 5 simulated minutes, AddressSanitizer's quarantine of freed memory
// kept to 1 MB, or its filling (256 MB by default) would be the memory growth measured, and no
// check of the CPU per simulated second (printed; the Release build checks it).
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"

#if TACTILE_SANITIZED
// Read by AddressSanitizer at start-up; ASAN_OPTIONS in the environment still overrides it.
extern "C" const char* __asan_default_options() {
  return "quarantine_size_mb=1";
}
#endif

namespace tactile::rig {
namespace {

// Resident set size of this process now (kB), from /proc/self/status.
long resident_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

double cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

double soak_sim_s() {
  const char* v = std::getenv("TACTILE_SOAK_SIM_S");
#if TACTILE_SANITIZED
  constexpr double kDefault = 5.0 * 60.0;  // two to three times slower under the sanitizers
#else
  constexpr double kDefault = 30.0 * 60.0;
#endif
  return v != nullptr ? std::stod(v) : kDefault;
}

TEST(LockstepSoak, ThirtySimulatedMinutesSameReportEveryTimeMemoryBoundedScoresAddUp) {
  const Scenario scenario =
      load_scenario(std::string(TACTILE_SOURCE_DIR) + "/rig/scenarios/default.yaml");
  const double target_s = soak_sim_s();
  std::string first_report;
  double sim_s = 0;
  int runs = 0;
  long rss_after_warmup = 0;
  long rss_max = 0;
  std::vector<double> cpu_per_sim_s;
  while (sim_s < target_s) {
    const double c0 = cpu_s();
    const LockstepResult r = run_lockstep(scenario);
    const double c1 = cpu_s();
    ++runs;
    const Report& rep = r.report;
    sim_s += rep.sim_time_s;
    cpu_per_sim_s.push_back((c1 - c0) / rep.sim_time_s);
    ASSERT_TRUE(r.physics_finite) << "run " << runs;
    ASSERT_TRUE(rep.completed) << "run " << runs << ": " << rep.end_reason;
    const std::string json = report_json(rep);
    if (runs == 1) {
      first_report = json;
    } else {
      ASSERT_EQ(json, first_report) << "run " << runs << " differs from the first";
    }
    // The scores add up: the per-frame counts sum to the totals, one sample per frame.
    ASSERT_EQ(r.series.frames.size(), rep.frames) << "run " << runs;
    std::uint64_t tp = 0, fp = 0, fn = 0;
    for (const FrameSample& f : r.series.frames) {
      for (std::size_t t = 0; t < kFingertips; ++t) {
        tp += f.tp[t];
        fp += f.fp[t];
        fn += f.fn[t];
      }
    }
    EXPECT_EQ(tp, rep.slip.true_positives) << "run " << runs;
    EXPECT_EQ(fp, rep.slip.false_positives) << "run " << runs;
    EXPECT_EQ(fn, rep.slip.false_negatives) << "run " << runs;
    const long rss = resident_kb();
    ASSERT_GT(rss, 0);
    if (runs == 2) rss_after_warmup = rss;
    rss_max = std::max(rss_max, rss);
    if (runs > 2) {
      // Bound measured on this machine: the resident set after the second run plus 8 MiB
      // (runs 3.. stayed within 1 MiB of it; docs/reliability.md).
      ASSERT_LE(rss, rss_after_warmup + 8 * 1024)
          << "run " << runs << ": resident " << rss << " kB, after run 2 " << rss_after_warmup;
    }
    std::fprintf(stderr,
                 "[soak] run %d: %.1f s simulated (total %.0f of %.0f s), resident %ld kB, %.3f "
                 "CPU s per simulated s\n",
                 runs, rep.sim_time_s, sim_s, target_s, rss, cpu_per_sim_s.back());
  }
  ASSERT_GE(runs, 2);
  // No drift in speed: the last runs cost no more CPU per simulated second than the first
  // ones, allowing for a shared machine.
  const std::size_t third = std::max<std::size_t>(1, cpu_per_sim_s.size() / 3);
  auto median_of = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double early =
      median_of({cpu_per_sim_s.begin(), cpu_per_sim_s.begin() + static_cast<long>(third)});
  const double late =
      median_of({cpu_per_sim_s.end() - static_cast<long>(third), cpu_per_sim_s.end()});
#if !TACTILE_SANITIZED
  // Not under the sanitizers: five or six runs whose CPU time on a loaded machine, with
  // AddressSanitizer's bookkeeping, varies more than the drift this looks for (1.61 times was
  // seen in CI with other work beside it).
  EXPECT_LE(late, 1.5 * early) << "CPU per simulated second went from " << early << " to " << late;
#endif
  std::fprintf(stderr,
               "[soak] %d runs, %.0f s simulated; resident after run 2 %ld kB, max %ld kB; CPU "
               "per simulated s early %.3f late %.3f\n",
               runs, sim_s, rss_after_warmup, rss_max, early, late);
}

}  // namespace
}  // namespace tactile::rig
