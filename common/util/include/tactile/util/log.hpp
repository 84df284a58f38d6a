#pragma once

// Logging for programs: one line per message on standard error, with a UTC time stamp,
// the program name and a level. Never used in per-frame paths of the cores.
#include <fmt/core.h>

#include <string>
#include <string_view>

namespace tactile::util {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

void set_program_name(std::string_view name);
// The name given to set_program_name ("tactile" before any): what log lines and error messages
// start with.
std::string program_name();
void set_log_level(LogLevel level);
LogLevel log_level();
// Parses "debug", "info", "warn", "error"; throws std::invalid_argument otherwise.
LogLevel parse_log_level(std::string_view text);
void log_line(LogLevel level, std::string_view message);

template <typename... Args>
void log_debug(fmt::format_string<Args...> f, Args&&... args) {
  if (log_level() <= LogLevel::kDebug)
    log_line(LogLevel::kDebug, fmt::format(f, std::forward<Args>(args)...));
}
template <typename... Args>
void log_info(fmt::format_string<Args...> f, Args&&... args) {
  if (log_level() <= LogLevel::kInfo)
    log_line(LogLevel::kInfo, fmt::format(f, std::forward<Args>(args)...));
}
template <typename... Args>
void log_warn(fmt::format_string<Args...> f, Args&&... args) {
  if (log_level() <= LogLevel::kWarn)
    log_line(LogLevel::kWarn, fmt::format(f, std::forward<Args>(args)...));
}
template <typename... Args>
void log_error(fmt::format_string<Args...> f, Args&&... args) {
  log_line(LogLevel::kError, fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace tactile::util
