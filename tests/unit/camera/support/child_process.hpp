#pragma once

// A child process for tests (util::Process): started with its output captured, killed
// (SIGKILL) and reaped when the object goes, and killed by the kernel if the test process dies
// first (PR_SET_PDEATHSIG), so no test leaves a process behind.
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "tactile/util/process.hpp"

namespace tactile::camera::testing {

class ChildProcess {
 public:
  // argv[0] is looked up in PATH. Throws std::runtime_error when it is not found or cannot start.
  explicit ChildProcess(std::vector<std::string> argv);

  // Waits for the exit within `timeout`, reading its output meanwhile. The exit status, or
  // nothing when it still runs (the caller then stops it).
  std::optional<int> wait_exit(std::chrono::milliseconds timeout) {
    return process_.wait_for(timeout);
  }
  // SIGTERM, then SIGKILL when it has not exited within `grace`. Returns the exit status
  // (128 + signal number for a signal).
  int stop(std::chrono::milliseconds grace = std::chrono::milliseconds(2000)) {
    return process_.stop(grace);
  }
  bool running() { return process_.running(); }
  // Standard output and error, interleaved, as read so far.
  const std::string& output() { return process_.output(); }
  pid_t pid() const { return process_.pid(); }

 private:
  util::Process process_;
};

// Runs a program to its end within `timeout` (killing it otherwise); returns exit status and
// output.
struct RunResult {
  int status = -1;
  bool timed_out = false;
  std::string output;
};
RunResult run_program(std::vector<std::string> argv, std::chrono::milliseconds timeout);

}  // namespace tactile::camera::testing
