#include "tactile/util/process.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "tactile/util/clock.hpp"

extern char** environ;

namespace tactile::util {
namespace {

// What a child reports through the error pipe when it cannot reach exec.
enum class Step : int { exec = 0, scheduling = 1 };
struct ChildError {
  Step step;
  int error;
};

int open_redirect(const Redirect& r, int standard_fd) {
  switch (r.to) {
    case Redirect::To::null:
      return ::open("/dev/null", (standard_fd == 0 ? O_RDONLY : O_WRONLY) | O_CLOEXEC);
    case Redirect::To::file:
      return ::open(r.path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    case Redirect::To::append:
      return ::open(r.path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    default:
      return -1;
  }
}

bool opens_a_file(const Redirect& r) {
  return r.to == Redirect::To::null || r.to == Redirect::To::file || r.to == Redirect::To::append;
}

void close_all(std::initializer_list<int> fds) {
  for (const int fd : fds)
    if (fd >= 0) ::close(fd);
}

void check(const ProcessOptions& o) {
  if (o.argv.empty() || o.argv.front().empty())
    throw std::invalid_argument("Process: no program to start");
  if (o.stdin_from.to != Redirect::To::inherit && o.stdin_from.to != Redirect::To::null)
    throw std::invalid_argument("Process: standard input is inherited or /dev/null");
  if (o.stdout_to.to == Redirect::To::standard_output || o.stderr_to.to == Redirect::To::pipe)
    throw std::invalid_argument(
        "Process: only standard output takes a pipe, only standard error follows it");
}

// The child's side, between fork and exec: async-signal-safe calls only (the parent may have
// threads). Never returns.
[[noreturn]] void become_child(const ProcessOptions& o, pid_t parent, const int (&fds)[3],
                               int error_fd, char* const* argv, char* const* envp) {
  if (o.die_with_parent) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the parent died before prctl
  }
  if (o.own_process_group) ::setpgid(0, 0);
  for (int s = 0; s < 3; ++s)
    if (fds[s] >= 0) ::dup2(fds[s], s);
  if (o.stderr_to.to == Redirect::To::standard_output) ::dup2(1, 2);
  ChildError e{Step::exec, 0};
  const sched_param normal{};
  if (o.normal_scheduling && ::sched_setscheduler(0, SCHED_OTHER, &normal) != 0) {
    e = {Step::scheduling, errno};
  } else {
    ::execvpe(argv[0], argv, envp);
    e.error = errno;
  }
  (void)!::write(error_fd, &e, sizeof e);
  ::_exit(127);
}

}  // namespace

int exit_status_of(int raw_status) {
  if (WIFEXITED(raw_status)) return WEXITSTATUS(raw_status);
  if (WIFSIGNALED(raw_status)) return 128 + WTERMSIG(raw_status);
  return -1;
}

Process::Process(ProcessOptions options) : options_(std::move(options)) {
  check(options_);
  const std::string& program = options_.argv.front();
  // Everything the child needs is prepared before fork.
  std::vector<char*> argv;
  for (std::string& a : options_.argv)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_store;
  std::vector<char*> env;
  if (!options_.extra_env.empty()) {
    for (char** e = environ; *e != nullptr; ++e)
      env_store.emplace_back(*e);
    env_store.insert(env_store.end(), options_.extra_env.begin(), options_.extra_env.end());
    for (std::string& e : env_store)
      env.push_back(e.data());
    env.push_back(nullptr);
  }
  const Redirect* redirects[3] = {&options_.stdin_from, &options_.stdout_to, &options_.stderr_to};
  int fds[3] = {-1, -1, -1};
  int out_pipe[2] = {-1, -1};
  int error_pipe[2] = {-1, -1};
  for (int s = 0; s < 3; ++s) {
    if (!opens_a_file(*redirects[s])) continue;
    fds[s] = open_redirect(*redirects[s], s);
    if (fds[s] < 0) {
      const int error = errno;
      close_all({fds[0], fds[1], fds[2]});
      throw std::runtime_error(fmt::format("cannot start {}: {}: {}", program,
                                           redirects[s]->path.string(), std::strerror(error)));
    }
  }
  if ((options_.stdout_to.to == Redirect::To::pipe && ::pipe2(out_pipe, O_CLOEXEC) != 0) ||
      ::pipe2(error_pipe, O_CLOEXEC) != 0) {
    const int error = errno;
    close_all({fds[0], fds[1], fds[2], out_pipe[0], out_pipe[1]});
    throw std::runtime_error(
        fmt::format("cannot start {}: pipe: {}", program, std::strerror(error)));
  }
  if (out_pipe[1] >= 0) fds[1] = out_pipe[1];
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ == 0) {
    become_child(options_, parent, fds, error_pipe[1], argv.data(),
                 env.empty() ? environ : env.data());
  }
  const int fork_error = errno;
  close_all({fds[0], fds[1], fds[2], error_pipe[1]});
  pipe_fd_ = out_pipe[0];
  if (pid_ < 0) {
    close_all({error_pipe[0], pipe_fd_});
    pipe_fd_ = -1;
    throw std::runtime_error(
        fmt::format("cannot start {}: fork: {}", program, std::strerror(fork_error)));
  }
  // The error pipe closes at exec (O_CLOEXEC); a child that cannot get there writes why first.
  ChildError e{};
  ssize_t n = 0;
  while ((n = ::read(error_pipe[0], &e, sizeof e)) < 0 && errno == EINTR) {
  }
  ::close(error_pipe[0]);
  if (n == static_cast<ssize_t>(sizeof e)) {
    kill();
    close_all({pipe_fd_});
    pipe_fd_ = -1;
    throw std::runtime_error(fmt::format(
        "cannot start {}: {}{}", program,
        e.step == Step::scheduling ? "cannot restore SCHED_OTHER: " : "", std::strerror(e.error)));
  }
}

Process::Process(Process&& other) noexcept
    : options_(std::move(other.options_)),
      pid_(other.pid_),
      pipe_fd_(other.pipe_fd_),
      status_(other.status_),
      output_(std::move(other.output_)) {
  other.pid_ = -1;
  other.pipe_fd_ = -1;
}

Process::~Process() {
  if (pid_ > 0 && !status_) {
    if (options_.destroy_grace.count() > 0) {
      stop(options_.destroy_grace);
    } else {
      kill();
    }
  }
  if (pipe_fd_ >= 0) ::close(pipe_fd_);
}

void Process::reaped(int raw_status) {
  status_ = exit_status_of(raw_status);
}

bool Process::running() {
  if (status_ || pid_ <= 0) return false;
  int raw = 0;
  if (::waitpid(pid_, &raw, WNOHANG) == pid_) reaped(raw);
  return !status_;
}

void Process::signal(int sig) {
  if (running()) ::kill(pid_, sig);
}

std::optional<int> Process::wait_for(std::chrono::milliseconds timeout) {
  const std::int64_t deadline = monotonic_ns() + timeout.count() * 1'000'000LL;
  while (running()) {
    const std::int64_t left_ms = (deadline - monotonic_ns()) / 1'000'000LL;
    if (left_ms <= 0) return std::nullopt;
    if (pipe_fd_ >= 0) {
      read_pipe(static_cast<int>(std::min<std::int64_t>(left_ms, 20)));
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::min<std::int64_t>(left_ms, 5)));
    }
  }
  drain_pipe_after_exit();
  return status_;
}

int Process::stop(std::chrono::milliseconds grace) {
  signal(options_.stop_signal);
  if (wait_for(grace)) return *status_;
  return kill();
}

int Process::kill() {
  if (!status_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int raw = 0;
    pid_t r = 0;
    while ((r = ::waitpid(pid_, &raw, 0)) < 0 && errno == EINTR) {
    }
    if (r == pid_) reaped(raw);
    drain_pipe_after_exit();
  }
  return status_.value_or(-1);
}

const std::string& Process::output() {
  for (int i = 0; i < 64 && pipe_fd_ >= 0; ++i) {
    const std::size_t before = output_.size();
    read_pipe(0);
    if (output_.size() == before) break;
  }
  return output_;
}

void Process::read_pipe(int timeout_ms) {
  if (pipe_fd_ < 0) return;
  pollfd p{pipe_fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return;
  char buffer[4096];
  const ssize_t n = ::read(pipe_fd_, buffer, sizeof buffer);
  if (n > 0) {
    output_.append(buffer, static_cast<std::size_t>(n));
  } else if (n == 0) {
    ::close(pipe_fd_);
    pipe_fd_ = -1;
  }
}

void Process::drain_pipe_after_exit() {
  // What it wrote before it ended; a grandchild that holds the pipe open does not hold us long.
  for (int i = 0; i < 50 && pipe_fd_ >= 0; ++i)
    read_pipe(10);
}

}  // namespace tactile::util
