#include "tactile/util/log.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <stdexcept>
#include <string>

#include "tactile/util/repeat_limiter.hpp"

namespace tactile::util {
namespace {

std::atomic<LogLevel> g_level{LogLevel::kInfo};
std::mutex g_mutex;
std::string g_program = "tactile";
// Warnings and errors repeat at most once a second, counted in between (a fault met on every
// frame would otherwise fill the log; docs/tools.md).
RepeatLimiter g_repeats;

const char* level_name(LogLevel l) {
  switch (l) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarn:
      return "warn";
    case LogLevel::kError:
      return "error";
  }
  return "?";
}

}  // namespace

void set_program_name(std::string_view name) {
  std::lock_guard lock(g_mutex);
  g_program = std::string(name);
}

std::string program_name() {
  std::lock_guard lock(g_mutex);
  return g_program;
}

void set_log_level(LogLevel level) {
  g_level = level;
}
LogLevel log_level() {
  return g_level;
}

LogLevel parse_log_level(std::string_view text) {
  if (text == "debug") return LogLevel::kDebug;
  if (text == "info") return LogLevel::kInfo;
  if (text == "warn") return LogLevel::kWarn;
  if (text == "error") return LogLevel::kError;
  throw std::invalid_argument("log level must be debug, info, warn or error, is '" +
                              std::string(text) + "'");
}

void log_line(LogLevel level, std::string_view message) {
  const auto now = std::chrono::system_clock::now();
  const std::time_t secs = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%H:%M:%S", &tm);
  std::lock_guard lock(g_mutex);
  std::string repeated;
  if (level >= LogLevel::kWarn) {
    const std::int64_t steady_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                       std::chrono::steady_clock::now().time_since_epoch())
                                       .count();
    const RepeatLimiter::Decision d = g_repeats.offer(message, steady_ns);
    if (!d.write) return;
    repeated = repeated_suffix(d.held_back);
  }
  std::fprintf(stderr, "%s.%03lldZ %s %s: %.*s%s\n", stamp, static_cast<long long>(ms),
               g_program.c_str(), level_name(level), static_cast<int>(message.size()),
               message.data(), repeated.c_str());
  std::fflush(stderr);
}

}  // namespace tactile::util
