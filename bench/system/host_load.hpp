#pragma once

// The latency benchmark's view of the machine while it measures (docs/benchmarks.md, "Latency
// and load"): CPU and major page faults of processes from /proc/PID/stat, the I/O stalls of every
// task from /proc, and a probe thread that sees the whole machine pause (the host's steal time and
// the load average are the real-time rig's too: tactile/util/host_load.hpp). Reads /proc and the
// clocks: the benchmark's side, not the pure analysis.
#include <sched.h>
#include <sys/types.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <map>
#include <stop_token>
#include <string>
#include <thread>

#include "tactile/util/clock.hpp"

namespace tactile::bench {

// Time during which every runnable task of this machine waited for I/O at once (the "full" line
// of /proc/pressure/io), in ms: a stall of every process, as when evicted code pages are read back.
double io_full_stall_ms();

// utime + stime of a process (all its threads), in seconds, and its major page faults.
struct ProcStat {
  double cpu_s = std::nan("");  // utime + stime, all threads
  double major_faults = std::nan("");
};

// CPU seconds and major faults of a process so far (NaN when it is gone).
ProcStat proc_stat(pid_t pid);

// CPU of processes over a window; sampled now and then, so that a process that ends before the
// window does (the task finished) is still measured up to its last sample.
// Also counts major page faults: each one stalled a thread of the process while a page (of its
// code or data, evicted by the kernel) was read back from disk.
struct CpuWindow {
  std::map<std::string, ProcStat> start;
  std::map<std::string, ProcStat> last;
  std::map<std::string, std::int64_t> last_ns;
  std::int64_t start_ns = 0;
  void begin(const std::map<std::string, pid_t>& pids) {
    start_ns = util::monotonic_ns();
    for (const auto& [name, pid] : pids) {
      start[name] = last[name] = proc_stat(pid);
      last_ns[name] = start_ns;
    }
  }
  void sample(const std::map<std::string, pid_t>& pids) {
    const std::int64_t now = util::monotonic_ns();
    for (const auto& [name, pid] : pids) {
      const ProcStat v = proc_stat(pid);
      if (!std::isfinite(v.cpu_s)) continue;  // gone
      last[name] = v;
      last_ns[name] = now;
    }
  }
  // Percent of one core per process, from the start to its last sample.
  std::map<std::string, double> end(const std::map<std::string, pid_t>& pids) {
    sample(pids);
    std::map<std::string, double> pct;
    for (const auto& [name, pid] : pids) {
      const double wall = static_cast<double>(last_ns[name] - start_ns) * 1e-9;
      if (wall > 0.5) pct[name] = 100.0 * (last[name].cpu_s - start[name].cpu_s) / wall;
    }
    return pct;
  }
  // Major page faults per process from the start to its last sample (call after end()).
  std::map<std::string, double> major_faults() const {
    std::map<std::string, double> n;
    for (const auto& [name, st] : last)
      n[name] = st.major_faults - start.at(name).major_faults;
    return n;
  }
};

// A thread that sleeps 1 ms at a time at real-time priority (SCHED_FIFO 1, when allowed) and
// records how late it wakes. Nothing else on the machine can keep it from running, so a wake-up
// tens of milliseconds late means the whole machine did not run (the host paused it), whatever
// its steal counter says. It costs a thousand short wake-ups a second.
class StallProbe {
 public:
  StallProbe()
      : thread_([this](const std::stop_token& stop) {
          sched_param fifo{};
          fifo.sched_priority = 1;
          fifo_ = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &fifo) == 0;
          constexpr std::int64_t kSleepNs = 1'000'000;
          while (!stop.stop_requested()) {
            const std::int64_t t0 = util::monotonic_ns();
            const timespec d{0, kSleepNs};
            ::clock_nanosleep(CLOCK_MONOTONIC, 0, &d, nullptr);
            const std::int64_t late = util::monotonic_ns() - t0 - kSleepNs;
            if (late > max_late_ns_.load()) {
              max_late_ns_ = late;
              max_at_ns_ = util::realtime_ns();
            }
            if (late > 10'000'000) ++stalls_;
          }
        }) {}
  StallProbe(const StallProbe&) = delete;
  StallProbe& operator=(const StallProbe&) = delete;
  void stop() {
    thread_.request_stop();
    if (thread_.joinable()) thread_.join();
  }
  double max_late_ms() const { return static_cast<double>(max_late_ns_.load()) * 1e-6; }
  std::int64_t max_at_ns() const { return max_at_ns_.load(); }
  std::uint64_t stalls_over_10ms() const { return stalls_.load(); }
  bool fifo() const { return fifo_.load(); }

 private:
  std::atomic<std::int64_t> max_late_ns_{0};
  std::atomic<std::int64_t> max_at_ns_{0};
  std::atomic<std::uint64_t> stalls_{0};
  std::atomic<bool> fifo_{false};
  std::jthread thread_;  // last: starts after the members it writes
};

}  // namespace tactile::bench
