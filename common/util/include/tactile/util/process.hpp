#pragma once

// The one process launcher of the project: the benchmarks, the sweep and the tests start their
// child programs with it (docs/architecture.md, rule 9). A child starts with the arguments and
// environment given, its standard streams where asked, in its own process group if asked, and
// is killed by the kernel when its parent dies (PR_SET_PDEATHSIG) unless told otherwise; the
// object stops it when it goes, and every wait has a deadline.
#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tactile::util {

// Where one of a child's standard streams goes.
struct Redirect {
  enum class To {
    inherit,          // this process's own stream
    null,             // /dev/null
    file,             // `path`, truncated
    append,           // `path`, appended to
    pipe,             // a pipe this process reads (Process::output); standard output only
    standard_output,  // wherever standard output goes; standard error only
  };
  To to = To::inherit;
  std::filesystem::path path;

  static Redirect inherit() { return {To::inherit, {}}; }
  static Redirect null() { return {To::null, {}}; }
  static Redirect file(std::filesystem::path p) { return {To::file, std::move(p)}; }
  static Redirect append(std::filesystem::path p) { return {To::append, std::move(p)}; }
  static Redirect pipe() { return {To::pipe, {}}; }
  static Redirect standard_output() { return {To::standard_output, {}}; }
};

struct ProcessOptions {
  // argv[0] is looked up in PATH when it has no slash.
  std::vector<std::string> argv;
  // NAME=VALUE entries added after this process's environment (a repeated name: the last wins).
  std::vector<std::string> extra_env;
  Redirect stdin_from = Redirect::inherit();  // inherit or null
  Redirect stdout_to = Redirect::inherit();
  Redirect stderr_to = Redirect::inherit();
  // A process group of its own: a Ctrl-C at the terminal then reaches this process alone, which
  // stops its children itself.
  bool own_process_group = false;
  // SIGKILL from the kernel when the thread that started it ends (PR_SET_PDEATHSIG), so that no
  // child outlives a test or a benchmark that dies.
  bool die_with_parent = true;
  // SCHED_OTHER in the child whatever the starting thread's policy (SCHED_IDLE, SCHED_FIFO).
  bool normal_scheduling = false;
  // stop()'s first signal.
  int stop_signal = SIGTERM;
  // The destructor stops a child still running with stop(destroy_grace); zero kills it at once.
  std::chrono::milliseconds destroy_grace{0};
};

class Process {
 public:
  // Starts the program. Throws std::runtime_error "cannot start PROGRAM: why" when it cannot
  // (not found, not executable, an output file that cannot be opened), and
  // std::invalid_argument for options that do not make sense (no argv, a pipe for stdin).
  explicit Process(ProcessOptions options);
  ~Process();
  Process(Process&& other) noexcept;
  Process& operator=(Process&&) = delete;
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  // Whether it still runs; reaps it, without waiting, once it has ended.
  bool running();
  // Sends `sig` to the process (not its group) while it runs.
  void signal(int sig);
  // Waits until it ends, at most `timeout`, reading the pipe meanwhile: its exit status, or
  // nothing when it still runs.
  std::optional<int> wait_for(std::chrono::milliseconds timeout);
  // The stop signal, then SIGKILL when it has not ended within `grace`; its exit status.
  int stop(std::chrono::milliseconds grace);
  // SIGKILL, and waits for it: its exit status.
  int kill();
  // The exit code, or 128 + the signal's number when a signal ended it; nothing while it runs.
  std::optional<int> exit_status() const { return status_; }
  // With Redirect::pipe: what it wrote so far (read now, without waiting); otherwise empty.
  const std::string& output();

 private:
  void reaped(int raw_status);
  // Reads what the pipe holds, waiting at most `timeout_ms` for the first bytes.
  void read_pipe(int timeout_ms);
  void drain_pipe_after_exit();

  ProcessOptions options_;
  pid_t pid_ = -1;
  int pipe_fd_ = -1;
  std::optional<int> status_;
  std::string output_;
};

// The exit status of a raw waitpid status: the exit code, or 128 + the signal's number.
int exit_status_of(int raw_status);

}  // namespace tactile::util
