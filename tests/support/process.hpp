#pragma once

// Runs real programs from tests (with util::Process): arguments as given, standard output and
// error captured to files, a deadline on every wait, and the process killed if a test ends early.
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tactile/util/process.hpp"

namespace tactile::testing {

struct ProcessResult {
  int exit_code = -1;  // exit status, or 128 + signal number
  bool timed_out = false;
  std::string out;
  std::string err;
};

class Process {
 public:
  // Starts argv[0] (looked up in PATH when it has no slash) with the arguments. Standard input is
  // /dev/null. The child is killed (SIGKILL) if the test process dies first. Throws
  // std::runtime_error when the program cannot start.
  explicit Process(std::vector<std::string> argv, std::vector<std::string> extra_env = {});
  ~Process();  // kills (SIGKILL) a process still running
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return process_->pid(); }
  bool running() { return process_->running(); }
  void signal(int sig) { process_->signal(sig); }
  // Waits until exit or the deadline; on timeout kills the process and says so.
  ProcessResult wait(std::chrono::milliseconds timeout);
  // What the process wrote so far.
  std::string out_so_far() const;
  std::string err_so_far() const;

 private:
  std::filesystem::path dir_;  // before process_: the files outlive the process
  std::optional<util::Process> process_;
};

// Runs to completion (bounded).
ProcessResult run(std::vector<std::string> argv,
                  std::chrono::milliseconds timeout = std::chrono::seconds(60));

// A fresh temporary directory removed when the object goes.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Whether this machine lets a process take SCHED_FIFO at `priority` (and, with `lock`, lock its
// memory: root, CAP_SYS_NICE and CAP_IPC_LOCK, or rtprio and memlock limits): tried in a child,
// which exits. Never pass `lock` in a sanitizer build: mlockall would fault in the shadow memory.
bool realtime_allowed(int priority, bool lock);

// A thread of a running process: its name, scheduling policy and real-time priority.
struct ThreadScheduling {
  std::string name;
  int policy = -1;
  int priority = -1;
};
// Every thread of `pid`, from /proc/PID/task/*/{comm,stat}.
std::vector<ThreadScheduling> thread_scheduling(pid_t pid);

// The line sensor_node and hand_node log once their realtime section took effect, e.g.
// "real-time scheduling: SCHED_FIFO priority 7, memory locked".
std::string realtime_log_line(int priority, bool lock);

}  // namespace tactile::testing
