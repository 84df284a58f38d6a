#include "host_load.hpp"

#include <fmt/format.h>
#include <unistd.h>

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

}  // namespace tactile::bench
