#include "child_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "tactile/util/clock.hpp"

namespace tactile::camera::testing {

namespace {

std::string find_in_path(const std::string& name) {
  if (name.find('/') != std::string::npos) return name;
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  std::size_t begin = 0;
  while (begin <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', begin), dirs.size());
    const std::string candidate = dirs.substr(begin, end - begin) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    begin = end + 1;
  }
  throw std::runtime_error("program '" + name + "' not found in PATH (" + dirs + ")");
}

int decode_status(int raw) {
  if (WIFEXITED(raw)) return WEXITSTATUS(raw);
  if (WIFSIGNALED(raw)) return 128 + WTERMSIG(raw);
  return -1;
}

}  // namespace

ChildProcess::ChildProcess(std::vector<std::string> argv) {
  if (argv.empty()) throw std::runtime_error("ChildProcess: empty command");
  const std::string program = find_in_path(argv.front());
  std::vector<char*> args;
  for (auto& a : argv)
    args.push_back(a.data());
  args.push_back(nullptr);

  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  }
  if (pid == 0) {
    // Only async-signal-safe calls between fork and exec (the parent may have threads).
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    ::dup2(fds[1], STDOUT_FILENO);
    ::dup2(fds[1], STDERR_FILENO);
    ::execv(program.c_str(), args.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  pid_ = pid;
  output_fd_ = fds[0];
}

ChildProcess::~ChildProcess() {
  if (!status_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int raw = 0;
    while (::waitpid(pid_, &raw, 0) < 0 && errno == EINTR) {
    }
  }
  if (output_fd_ >= 0) ::close(output_fd_);
}

void ChildProcess::read_available(int timeout_ms) {
  if (output_fd_ < 0) return;
  pollfd p{output_fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return;
  char buffer[4096];
  const ssize_t n = ::read(output_fd_, buffer, sizeof(buffer));
  if (n > 0) {
    output_.append(buffer, static_cast<std::size_t>(n));
  } else if (n == 0) {
    ::close(output_fd_);
    output_fd_ = -1;
  }
}

bool ChildProcess::running() {
  if (status_) return false;
  int raw = 0;
  const pid_t r = ::waitpid(pid_, &raw, WNOHANG);
  if (r == pid_) status_ = decode_status(raw);
  return !status_;
}

std::optional<int> ChildProcess::wait_exit(std::chrono::milliseconds timeout) {
  const std::int64_t deadline = util::monotonic_ns() + timeout.count() * 1000000LL;
  while (running()) {
    const std::int64_t left_ms = (deadline - util::monotonic_ns()) / 1000000LL;
    if (left_ms <= 0) return std::nullopt;
    if (output_fd_ >= 0) {
      read_available(static_cast<int>(std::min<std::int64_t>(left_ms, 20)));
    } else {
      ::usleep(2000);  // output closed, process not yet reaped
    }
  }
  // Whatever the process wrote before it ended (a grandchild holding the pipe does not hold us).
  for (int i = 0; i < 50 && output_fd_ >= 0; ++i)
    read_available(10);
  return status_;
}

int ChildProcess::stop(std::chrono::milliseconds grace) {
  if (running()) {
    ::kill(pid_, SIGTERM);
    if (!wait_exit(grace)) {
      ::kill(pid_, SIGKILL);
      wait_exit(std::chrono::milliseconds(5000));
    }
  }
  return status_.value_or(-1);
}

const std::string& ChildProcess::output() {
  for (int i = 0; i < 64 && output_fd_ >= 0; ++i) {
    const std::size_t before = output_.size();
    read_available(0);
    if (output_.size() == before) break;
  }
  return output_;
}

RunResult run_program(std::vector<std::string> argv, std::chrono::milliseconds timeout) {
  ChildProcess child(std::move(argv));
  RunResult result;
  const auto status = child.wait_exit(timeout);
  if (status) {
    result.status = *status;
  } else {
    result.timed_out = true;
    result.status = child.stop(std::chrono::milliseconds(500));
  }
  result.output = child.output();
  return result;
}

}  // namespace tactile::camera::testing
