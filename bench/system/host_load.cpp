#include "host_load.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <fstream>
#include <iterator>
#include <sstream>

namespace tactile::bench {

// Time during which every runnable task of this machine waited for I/O at once (the "full" line
// of /proc/pressure/io), in ms: a stall of every process, as when evicted code pages are read back.
double io_full_stall_ms() {
  std::ifstream in("/proc/pressure/io");
  std::string line;
  while (std::getline(in, line)) {
    const auto at = line.find("total=");
    if (line.rfind("full", 0) == 0 && at != std::string::npos)
      return std::strtod(line.c_str() + at + 6, nullptr) * 1e-3;
  }
  return std::nan("");
}

// Time the host took this machine's CPUs away (the steal column of /proc/stat), in ms summed
// over all CPUs: a virtual machine not scheduled by its host stalls every process at once.
double steal_ms() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  std::array<double, 8> f{};
  in >> cpu;
  for (double& x : f)
    in >> x;
  if (!in || cpu != "cpu") return std::nan("");
  return f[7] * 1000.0 / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

ProcStat proc_stat(pid_t pid) {
  std::ifstream in(fmt::format("/proc/{}/stat", pid));
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = stat.rfind(')');
  if (close == std::string::npos) return {};
  std::istringstream fields(stat.substr(close + 2));
  std::string f;
  unsigned long long majflt = 0;
  unsigned long long utime = 0;
  unsigned long long stime = 0;
  // Fields after the command: state(3) ... majflt(12) ... utime(14) stime(15).
  int i = 3;
  for (; i <= 15 && fields >> f; ++i) {
    if (i == 12) majflt = std::stoull(f);
    if (i == 14) utime = std::stoull(f);
    if (i == 15) stime = std::stoull(f);
  }
  if (i <= 15) return {};
  return {static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK)),
          static_cast<double>(majflt)};
}

std::string load_average() {
  std::string load;
  std::getline(std::ifstream("/proc/loadavg"), load);
  return load;
}

}  // namespace tactile::bench
