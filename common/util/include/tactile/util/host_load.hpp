#pragma once

// How busy the machine was (docs/rig.md, "The machine's load"): the host's CPU steal from
// /proc/stat and the load average from /proc/loadavg. The parsing is pure (text in, figures out);
// the readers open /proc. Used by the real-time rig's report and the latency benchmark
// (docs/benchmarks.md, "Latency and load"): a late frame on a machine whose host took its CPUs
// away, or with more runnable tasks than cores, is the machine's doing, not the code's.
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

namespace tactile::util {

// The aggregate `cpu` line of /proc/stat, in clock ticks summed over all CPUs, and the number of
// CPUs (its `cpuN` lines).
struct CpuTimes {
  double steal = 0;  // the host ran something else on this machine's CPUs
  double total = 0;  // user, nice, system, idle, iowait, irq, softirq and steal
  int cores = 0;
};

// The figures of /proc/stat's text; nullopt when it has no `cpu` line of at least 8 numbers.
std::optional<CpuTimes> parse_proc_stat(std::string_view text);

// Percent of all CPU time between two readings that the host stole; NaN when no time passed.
double steal_percent(const CpuTimes& before, const CpuTimes& after);

// The 1-minute load average, the first number of /proc/loadavg's line; nullopt when it has none.
std::optional<double> parse_load_average_1m(std::string_view line);

// /proc/stat now (nullopt when it cannot be read).
std::optional<CpuTimes> read_cpu_times();

// Steal so far, in ms summed over all CPUs (NaN when /proc/stat cannot be read).
double steal_ms();

// /proc/loadavg's line.
std::string load_average();

// The machine over a run: its CPU steal share, the 1-minute load average at the end (the last
// minute of the run) and its CPUs. NaN or 0 when not known.
struct MachineLoad {
  double steal_pct = std::nan("");
  double load_average_1m = std::nan("");
  int cores = 0;
};

// Enough to explain a late frame: the host stole more than this share of the CPU time, or more
// tasks wanted to run than there are cores.
inline constexpr double kExplainingStealPct = 5.0;
bool explains_latency(const MachineLoad& m);

// "CPU steal 0.4 %, load average 1.10 on 2 cores".
std::string describe(const MachineLoad& m);

// A plain sentence when explains_latency(m) (naming the figure and its threshold); empty
// otherwise.
std::string latency_explanation(const MachineLoad& m);

// Reads /proc/stat at begin() and /proc/stat and /proc/loadavg at end().
class MachineLoadWindow {
 public:
  void begin() { start_ = read_cpu_times(); }
  MachineLoad end() const;

 private:
  std::optional<CpuTimes> start_;
};

}  // namespace tactile::util
