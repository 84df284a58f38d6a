// Soak in real time (docs/reliability.md, "Soak"): one sensor_node runs for ten minutes while
// the rig and hand_node perform the paper's task again and again (the rig's cameras go away
// between runs and sensor_node reopens them). Checked: every run completes; sensor_node's
// memory stays within a bound measured after the first run; latency does not drift; every
// camera frame gives exactly one TactileFrame and none is lost on the way (sequence numbers
// without gaps, each interval's SensorStats matching the frames that came). Runs in a private
// network namespace (127.0.0.2 and 127.0.0.3 on lo). TACTILE_SOAK_REALTIME_S overrides the
// wall time (s). Built with the sanitizers (TACTILE_SANITIZED): three minutes at 30 fps
// (TACTILE_SYSTEM_SCENARIO), the p99 bounds scaled to that rate, and the programs'
// AddressSanitizer quarantine of freed memory kept to 1 MB, or its filling (256 MB by default)
// would be the memory growth measured.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "process.hpp"
#include "tactile/util/host_load.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using testing::Process;
using testing::TempDir;

long resident_kb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

double soak_s() {
  const char* v = std::getenv("TACTILE_SOAK_REALTIME_S");
#if TACTILE_SANITIZED
  constexpr double kDefault = 180.0;
#else
  constexpr double kDefault = 600.0;
#endif
  return v != nullptr ? std::stod(v) : kDefault;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// How much of the machine the programs could have had: the share of wall time its CPUs were
// taken by the host (steal, /proc/stat) and in which some task here waited for a CPU (PSI,
// /proc/pressure/cpu "some"; -1 where the kernel has none). Read around each run, printed.
struct MachineLoad {
  std::optional<util::CpuTimes> cpu;  // /proc/stat (util::read_cpu_times)
  double waiting = -1;                // seconds some task waited for a CPU
  double wall = 0;                    // seconds

  static MachineLoad now() {
    MachineLoad m;
    m.wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    m.cpu = util::read_cpu_times();
    std::ifstream psi("/proc/pressure/cpu");
    std::string line;
    if (std::getline(psi, line)) {
      const auto at = line.find("total=");
      if (line.rfind("some", 0) == 0 && at != std::string::npos)
        m.waiting = std::stod(line.substr(at + 6)) / 1e6;
    }
    return m;
  }
  // "steal 3% of the CPUs, waiting 12%" from `before` to this.
  std::string since(const MachineLoad& before) const {
    const double wall_s = std::max(wall - before.wall, 1e-9);
    const auto percent = [](double share) {
      return std::to_string(std::lround(100 * share)) + "%";
    };
    const double steal =
        cpu && before.cpu ? util::steal_percent(*before.cpu, *cpu) / 100 : std::nan("");
    std::string text =
        "steal " + (std::isfinite(steal) ? percent(steal) : std::string("?")) + " of the CPUs";
    if (waiting >= 0 && before.waiting >= 0)
      text +=
          ", some task waiting " + percent((waiting - before.waiting) / wall_s) + " of the time";
    return text;
  }
};

// What the test sees of one sensor's stream.
struct Stream {
  std::uint64_t frames = 0;  // TactileFrames received
  std::uint64_t gaps = 0;    // sequence numbers skipped
  std::optional<std::uint64_t> last_sequence;
  // The previous SensorStats and the frames received when it came.
  std::optional<v1::SensorStats> last_stats;
  std::uint64_t frames_at_last_stats = 0;
  std::uint64_t intervals_checked = 0;
  std::uint64_t interval_mismatches = 0;  // intervals whose counts differ
  std::string first_mismatch;
};

TEST(RealtimeSoak, TenMinutesOfRunsMemoryBoundedLatencySteadyCountersAddUp) {
  // quick.yaml, or its 30 fps twin when built with the sanitizers.
  const std::string scenario = TACTILE_SYSTEM_SCENARIO;
#if TACTILE_SANITIZED
  {
    // The programs started below inherit it (appended, it wins over a quarantine set before).
    const char* given = std::getenv("ASAN_OPTIONS");
    const std::string options = std::string(given != nullptr ? given : "") +
                                (given != nullptr && *given != '\0' ? ":" : "") +
                                "quarantine_size_mb=1";
    ::setenv("ASAN_OPTIONS", options.c_str(), 1);
  }
#endif
  TempDir dir;
  const auto config = dir / "config";
  {
    const auto r = testing::run(
        {TACTILE_RIG_PATH, "--scenario", scenario, "--write-configs", config.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  zmq::context_t ctx;
  wire::Subscriber sub(ctx, {"tcp://127.0.0.1:5555"},
                       {wire::kFrameTopicPrefix, wire::kStatsTopicPrefix});
  Process sensor({TACTILE_SENSOR_NODE_PATH, "--config", (config / "sensor_node.yaml").string()});

  std::map<std::string, Stream> streams;
  wire::TopicMessage m;
  v1::Envelope env;
  const auto drain = [&](std::chrono::milliseconds timeout) {
    if (!sub.receive(m, timeout)) return;
    do {
      if (wire::decode(m.payload, env) != wire::DecodeStatus::kOk) {
        ADD_FAILURE() << "sensor_node sent an undecodable message on " << m.topic;
        continue;
      }
      if (env.has_tactile_frame()) {
        Stream& s = streams[env.tactile_frame().sensor_id()];
        const std::uint64_t seq = env.tactile_frame().sequence();
        if (s.last_sequence && seq != *s.last_sequence + 1) {
          s.gaps += seq > *s.last_sequence ? seq - *s.last_sequence - 1 : 1;
        }
        s.last_sequence = seq;
        ++s.frames;
      } else if (env.has_sensor_stats()) {
        const v1::SensorStats& st = env.sensor_stats();
        Stream& s = streams[st.sensor_id()];
        EXPECT_EQ(st.frames(), st.frames_complete() + st.frames_incomplete())
            << st.sensor_id() << ": the counters do not add up";
        // Over an interval without a camera restart, the camera's frame count rose by exactly
        // the TactileFrames that came (one per camera frame, none lost on the way).
        if (s.last_stats && s.last_stats->camera_restarts() == st.camera_restarts() &&
            st.frames() >= s.last_stats->frames()) {
          ++s.intervals_checked;
          const std::uint64_t counted = st.frames() - s.last_stats->frames();
          const std::uint64_t came = s.frames - s.frames_at_last_stats;
          if (counted != came) {
            if (s.interval_mismatches++ == 0) {
              s.first_mismatch = st.sensor_id() + ": camera frames " + std::to_string(counted) +
                                 ", TactileFrames " + std::to_string(came);
            }
          }
        }
        s.last_stats = st;
        s.frames_at_last_stats = s.frames;
      }
    } while (sub.receive(m, 0ms));
  };

  const auto start = std::chrono::steady_clock::now();
  const double limit_s = soak_s();
  int runs = 0;
  long rss_first = -1;
  long rss_max = 0;
  std::vector<double> p50s, p99s;
  std::vector<std::string> loads;  // per run, MachineLoad::since
  // Latency does not drift: the best of the later runs' p50s stays within three times the
  // earlier runs' median plus 2 ms. What this catches is growth that does not stop (a queue
  // filling, a leak slowing the loop): it makes every later run slower. The machine is shared
  // and its load comes and goes: p50 2.5 to 6 ms was seen with a build starting beside the test;
  // in a CI run five runs in the middle had p50 2 to 6 ms and one a p99 of 118 ms, then the level
  // came back to 1 ms by itself; a stop's CI, busy for minutes (other tests failing on time in the
  // same run), had the later half's median at 24 ms against 0.83. So one later run at the level
  // is enough, and while none is, the soak goes on for up to kExtraRuns more runs.
  constexpr int kExtraRuns = 4;
  struct Drift {
    double early;      // the earlier half's median p50
    double late_best;  // the later half's lowest
    double late;       // the later half's median
    bool steady() const { return late_best <= 3.0 * early + 2.0; }
  };
  const auto drift = [&] {
    const auto half = static_cast<long>(p50s.size() / 2);
    return Drift{median({p50s.begin(), p50s.begin() + half}),
                 *std::min_element(p50s.begin() + half, p50s.end()),
                 median({p50s.begin() + half, p50s.end()})};
  };
  int extra_runs = 0;
  while (true) {
    const bool in_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < limit_s;
    if (!in_time) {
      if (p50s.size() < 2 || drift().steady() || extra_runs == kExtraRuns) break;
      ++extra_runs;
    }
    ++runs;
    const MachineLoad load_before = MachineLoad::now();
    const auto report_path = dir / ("run-" + std::to_string(runs) + ".json");
    Process rig({TACTILE_RIG_PATH, "--scenario", scenario, "--report", report_path.string()});
    Process hand({TACTILE_HAND_NODE_PATH, "--config", (config / "hand_node.yaml").string()});
    const auto run_deadline = std::chrono::steady_clock::now() + 150s;
    while (hand.running() && std::chrono::steady_clock::now() < run_deadline)
      drain(50ms);
    const auto hr = hand.wait(5s);
    ASSERT_FALSE(hr.timed_out) << "run " << runs << ": hand_node still running\n"
                               << hr.err << "\n--- rig\n"
                               << rig.err_so_far();
    ASSERT_EQ(hr.exit_code, 0) << "run " << runs << "\n"
                               << hr.err << "\n--- rig\n"
                               << rig.err_so_far();
    while (rig.running() && std::chrono::steady_clock::now() < run_deadline + 60s)
      drain(50ms);
    const auto rr = rig.wait(5s);
    ASSERT_EQ(rr.exit_code, 0) << "run " << runs << "\n" << rr.err;
    ASSERT_TRUE(sensor.running()) << sensor.err_so_far();

    std::ifstream in(report_path);
    const json r = json::parse(in);
    ASSERT_EQ(r["completed"], true) << "run " << runs << ": " << r.dump();
    EXPECT_EQ(r["dropped"], false) << "run " << runs << ": " << r.dump();
    EXPECT_EQ(r["tightened_cycle"], r["true_tight_cycle"]) << "run " << runs << ": " << r.dump();
    ASSERT_TRUE(r["latency_ms"].is_object()) << r.dump();
    p50s.push_back(r["latency_ms"]["p50"].get<double>());
    p99s.push_back(r["latency_ms"]["p99"].get<double>());
    loads.push_back(MachineLoad::now().since(load_before));

    const long rss = resident_kb(sensor.pid());
    ASSERT_GT(rss, 0);
    if (runs == 1) rss_first = rss;
    rss_max = std::max(rss_max, rss);
    // Bound measured on this machine: sensor_node's resident set after the first run plus
    // 16 MiB (later runs stayed within a few hundred kB of it; docs/reliability.md).
    EXPECT_LE(rss, rss_first + 16 * 1024) << "run " << runs << ": sensor_node resident " << rss
                                          << " kB, after run 1 " << rss_first << " kB";
    std::fprintf(stderr,
                 "[soak] run %d at %.0f s: latency p50 %.2f ms p99 %.2f ms; sensor_node resident "
                 "%ld kB; machine: %s\n",
                 runs,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                 p50s.back(), p99s.back(), rss, loads.back().c_str());
  }
  drain(200ms);
  sensor.signal(SIGINT);
  const auto sr = sensor.wait(20s);
  EXPECT_EQ(sr.exit_code, 0) << sr.err;

  ASSERT_GE(runs, 2);
  const auto [early, late_best, late] = drift();
  std::string per_run;
  for (std::size_t i = 0; i < p50s.size(); ++i)
    per_run += "\n  run " + std::to_string(i + 1) + ": p50 " + std::to_string(p50s[i]) + " ms; " +
               loads[i];
  EXPECT_TRUE(drift().steady()) << "latency p50 went from " << early
                                << " ms (median of the earlier runs) to " << late_best
                                << " ms at best and " << late << " ms median in the later runs, "
                                << extra_runs << " runs added to wait for the level:" << per_run;
  // No more than one run's p99 reaches 100 ms (none 1 s).
  std::vector<double> sorted_p99s = p99s;
  std::sort(sorted_p99s.begin(), sorted_p99s.end(), std::greater<>());
#if TACTILE_SANITIZED
  // At 30 fps with programs two to three times slower, p50 is about 28 ms and a loaded machine
  // gave p99s of 148 and 232 ms in one soak: the same check, scaled.
  constexpr double kOneRunP99Ms = 4000.0, kTwoRunsP99Ms = 400.0;
#else
  constexpr double kOneRunP99Ms = 1000.0, kTwoRunsP99Ms = 100.0;
#endif
  EXPECT_LT(sorted_p99s[0], kOneRunP99Ms) << "a run's latency p99";
  EXPECT_LT(sorted_p99s[1], kTwoRunsP99Ms)
      << "two runs' latency p99 (the worst " << sorted_p99s[0] << " ms)";
  for (const auto& [id, s] : streams) {
    EXPECT_EQ(s.gaps, 0U) << id << ": TactileFrames lost between sensor_node and the test";
    EXPECT_GT(s.intervals_checked, 10U) << id;
    EXPECT_EQ(s.interval_mismatches, 0U) << s.first_mismatch;
    ASSERT_TRUE(s.last_stats);
    std::fprintf(stderr,
                 "[soak] %s: %llu TactileFrames, %llu stats intervals checked, %llu not matching, "
                 "%llu camera restarts\n",
                 id.c_str(), static_cast<unsigned long long>(s.frames),
                 static_cast<unsigned long long>(s.intervals_checked),
                 static_cast<unsigned long long>(s.interval_mismatches),
                 static_cast<unsigned long long>(s.last_stats->camera_restarts()));
  }
  EXPECT_EQ(streams.size(), 2U);
  std::fprintf(stderr,
               "[soak] %d runs (%d added) in %.0f s; latency p50 early %.2f ms, late %.2f ms (best "
               "%.2f ms), worst p99 %.2f ms; sensor_node resident after run 1 %ld kB, max %ld kB\n",
               runs, extra_runs,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
               early, late, late_best, *std::max_element(p99s.begin(), p99s.end()), rss_first,
               rss_max);
}

}  // namespace
}  // namespace tactile
