#include "tactile/util/host_load.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <charconv>
#include <fstream>
#include <iterator>
#include <sstream>

namespace tactile::util {
namespace {

// The columns of a /proc/stat cpu line up to steal (guest time is already counted in user).
enum CpuColumn : std::size_t {
  kUser,
  kNice,
  kSystem,
  kIdle,
  kIowait,
  kIrq,
  kSoftirq,
  kSteal,
  kColumns
};

std::string read_text(const char* path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

std::optional<CpuTimes> parse_proc_stat(std::string_view text) {
  std::optional<CpuTimes> times;
  int cores = 0;
  std::istringstream lines{std::string(text)};
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    std::string name;
    fields >> name;
    if (name.size() > 3 && name.starts_with("cpu")) ++cores;
    if (name != "cpu") continue;
    std::array<double, kColumns> f{};
    for (double& x : f)
      fields >> x;
    if (!fields) return std::nullopt;
    times = CpuTimes{f[kSteal], 0, 0};
    for (const double x : f)
      times->total += x;
  }
  if (times) times->cores = cores;
  return times;
}

double steal_percent(const CpuTimes& before, const CpuTimes& after) {
  const double total = after.total - before.total;
  if (!(total > 0)) return std::nan("");
  return 100.0 * (after.steal - before.steal) / total;
}

std::optional<double> parse_load_average_1m(std::string_view line) {
  double v = 0;
  const auto [end, ec] = std::from_chars(line.data(), line.data() + line.size(), v);
  if (ec != std::errc() || end == line.data()) return std::nullopt;
  return v;
}

std::optional<CpuTimes> read_cpu_times() {
  return parse_proc_stat(read_text("/proc/stat"));
}

double steal_ms() {
  const std::optional<CpuTimes> t = read_cpu_times();
  if (!t) return std::nan("");
  return t->steal * 1000.0 / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

std::string load_average() {
  std::string load;
  std::getline(std::ifstream("/proc/loadavg"), load);
  return load;
}

bool explains_latency(const MachineLoad& m) {
  return m.steal_pct > kExplainingStealPct ||
         (m.cores > 0 && m.load_average_1m > static_cast<double>(m.cores));
}

std::string describe(const MachineLoad& m) {
  return fmt::format("CPU steal {:.1f} %, load average {:.2f} on {} cores", m.steal_pct,
                     m.load_average_1m, m.cores);
}

std::string latency_explanation(const MachineLoad& m) {
  if (!explains_latency(m)) return {};
  std::string why;
  if (m.steal_pct > kExplainingStealPct) {
    why = fmt::format("the host took {:.1f} % of its CPU time away (steal above {:.0f} %)",
                      m.steal_pct, kExplainingStealPct);
  }
  if (m.cores > 0 && m.load_average_1m > static_cast<double>(m.cores)) {
    if (!why.empty()) why += " and ";
    why += fmt::format("{:.2f} tasks wanted its {} cores (load above the number of cores)",
                       m.load_average_1m, m.cores);
  }
  return fmt::format(
      "The machine was busy enough to explain a high latency and late frames: {}; they are "
      "then the machine's doing, not the system's.",
      why);
}

MachineLoad MachineLoadWindow::end() const {
  MachineLoad m;
  const std::optional<CpuTimes> now = read_cpu_times();
  if (now) m.cores = now->cores;
  if (start_ && now) m.steal_pct = steal_percent(*start_, *now);
  m.load_average_1m = parse_load_average_1m(load_average()).value_or(std::nan(""));
  return m;
}

}  // namespace tactile::util
