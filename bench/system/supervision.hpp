#pragma once

// The latency benchmark's programs as child processes (util::Process), its own threads'
// scheduling while it measures, and its progress lines on standard error.
#include <fmt/format.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tactile/util/process.hpp"
#include "tactile/util/realtime.hpp"

namespace tactile::bench {

namespace fs = std::filesystem;
using std::chrono::milliseconds;

inline void progress(const std::string& line) {
  std::fprintf(stderr, "system_latency_bench: %s\n", line.c_str());
}

// ------------------------------------------------------------------------------------------
// Child processes

// While it lives, the calling thread (and the threads it starts: a ZeroMQ context's I/O thread)
// runs under SCHED_IDLE, only when no other thread wants a CPU: the benchmark's own subscriber
// then does not compete with the programs it measures for this machine's two cores. Without the
// permission (root), the benchmark says so and runs at the normal policy.
class IdleScheduling {
 public:
  explicit IdleScheduling(bool wanted) {
    if (!wanted) return;
    // Without privilege a thread cannot leave SCHED_IDLE again (RLIMIT_NICE), and neither could
    // the programs forked from it: stay at the normal policy.
    if (::geteuid() != 0) {
      progress("not root: the benchmark's subscriber runs at the normal policy");
      return;
    }
    const sched_param none{};
    active_ = ::sched_setscheduler(0, SCHED_IDLE, &none) == 0;
    if (!active_)
      progress(
          fmt::format("cannot run the benchmark's subscriber under SCHED_IDLE ({}): it "
                      "competes with the programs for the CPUs",
                      std::strerror(errno)));
  }
  IdleScheduling(const IdleScheduling&) = delete;
  IdleScheduling& operator=(const IdleScheduling&) = delete;
  ~IdleScheduling() {
    const sched_param normal{};
    if (active_) ::sched_setscheduler(0, SCHED_OTHER, &normal);
  }
  bool active() const { return active_; }

 private:
  bool active_ = false;
};

// While it lives, the calling thread (and the threads it starts: Aravis's stream threads, a
// ZeroMQ context's) runs under SCHED_FIFO at `priority`, as sensor_node and hand_node do with
// --realtime-priority: the transport alone is then measured like for like. 0: nothing. Throws
// when the kernel refuses (the programs would refuse it too).
class FifoScheduling {
 public:
  explicit FifoScheduling(int priority) {
    if (priority == 0) return;
    util::apply_realtime_scheduling({priority, false}, "--realtime-priority");
    active_ = true;
  }
  FifoScheduling(const FifoScheduling&) = delete;
  FifoScheduling& operator=(const FifoScheduling&) = delete;
  ~FifoScheduling() {
    const sched_param normal{};
    if (active_) ::sched_setscheduler(0, SCHED_OTHER, &normal);
  }

 private:
  bool active_ = false;
};

// A program the benchmark runs (util::Process): standard input /dev/null, its output appended to
// `log`, at the normal policy whatever this thread's (IdleScheduling), killed if the benchmark
// dies; stopped with SIGINT, and SIGKILL after a timeout.
class Child {
 public:
  Child(std::string name, std::vector<std::string> argv, const fs::path& log)
      : name_(std::move(name)), process_(options(std::move(argv), log)) {}

  const std::string& name() const { return name_; }
  pid_t pid() const { return process_.pid(); }
  bool running() { return process_.running(); }
  // Exit code once the child has ended by itself, or was stopped `timeout` after the call.
  int wait(milliseconds timeout) {
    process_.wait_for(timeout);
    return stop(milliseconds(2000));
  }
  // Exit code (128 + signal when killed); SIGINT first, SIGKILL after `timeout`.
  int stop(milliseconds timeout) {
    process_.signal(SIGINT);
    if (const auto status = process_.wait_for(timeout)) return *status;
    progress(fmt::format("{} did not stop within {} ms of SIGINT: killed", name_, timeout.count()));
    return process_.kill();
  }
  int exit_code() const { return process_.exit_status().value_or(-1); }

 private:
  static util::ProcessOptions options(std::vector<std::string> argv, const fs::path& log) {
    util::ProcessOptions o;
    o.argv = std::move(argv);
    o.stdin_from = util::Redirect::null();
    o.stdout_to = util::Redirect::append(log);
    o.stderr_to = util::Redirect::standard_output();
    o.normal_scheduling = true;
    o.stop_signal = SIGINT;
    return o;
  }

  std::string name_;
  util::Process process_;
};

// The last `lines` lines of a log, each on a line of its own, indented.
inline std::string tail_of(const fs::path& log, std::size_t lines = 5) {
  std::ifstream in(log);
  std::vector<std::string> all;
  for (std::string l; std::getline(in, l);)
    all.push_back(l);
  std::string s;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i)
    s += "\n    " + all[i];
  return s;
}

}  // namespace tactile::bench
