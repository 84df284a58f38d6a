#pragma once

// Helpers of the tools' integration tests: waiting on a process's output, reading logs.
#include <chrono>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"
#include "tactile/recording/log_reader.hpp"

namespace tactile::tools_test {

// Polls `text()` until `pattern` matches (bounded); the first capture group, or nullopt.
template <typename Text>
std::optional<std::string> await_match(
    Text text, const std::string& pattern,
    std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const std::regex re(pattern);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    std::smatch m;
    const std::string t = text();
    if (std::regex_search(t, m, re)) return m.size() > 1 ? m[1].str() : m[0].str();
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

struct LogContents {
  v1::LogHeader header;
  std::vector<v1::LogRecord> records;
  recording::ReadStatus end = recording::ReadStatus::kEnd;
  std::map<std::string, int> per_topic;
};

inline LogContents read_log(const std::filesystem::path& path) {
  recording::LogReader r(path);
  LogContents c;
  c.header = r.header();
  v1::LogRecord rec;
  while ((c.end = r.next(rec)) == recording::ReadStatus::kRecord) {
    ++c.per_topic[rec.topic()];
    c.records.push_back(rec);
  }
  return c;
}

}  // namespace tactile::tools_test
