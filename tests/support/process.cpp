#include "process.hpp"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace tactile::testing {
namespace {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::filesystem::path make_temp_dir(const char* prefix) {
  std::string templ =
      (std::filesystem::temp_directory_path() / (std::string(prefix) + "XXXXXX")).string();
  if (::mkdtemp(templ.data()) == nullptr)
    throw std::runtime_error(std::string("mkdtemp: ") + std::strerror(errno));
  return templ;
}

}  // namespace

Process::Process(std::vector<std::string> argv, std::vector<std::string> extra_env)
    : dir_(make_temp_dir("tactile-proc-")) {
  const std::string out = (dir_ / "out").string();
  const std::string err = (dir_ / "err").string();
  // Everything the child needs is prepared before fork: after it, only async-signal-safe calls.
  const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  const int out_fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (null_fd < 0 || out_fd < 0 || err_fd < 0)
    throw std::runtime_error("cannot open the output files");
  std::vector<char*> args;
  for (auto& a : argv)
    args.push_back(a.data());
  args.push_back(nullptr);
  std::vector<std::string> env_store;
  for (char** e = environ; *e != nullptr; ++e)
    env_store.emplace_back(*e);
  for (auto& e : extra_env)
    env_store.push_back(e);
  std::vector<char*> env;
  for (auto& e : env_store)
    env.push_back(e.data());
  env.push_back(nullptr);
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid_ == 0) {
    // A test that dies takes its programs with it.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    ::dup2(null_fd, 0);
    ::dup2(out_fd, 1);
    ::dup2(err_fd, 2);
    ::execvpe(args[0], args.data(), env.data());
    ::_exit(127);
  }
  ::close(null_fd);
  ::close(out_fd);
  ::close(err_fd);
}

Process::~Process() {
  if (running()) {
    ::kill(pid_, SIGKILL);
    int st = 0;
    ::waitpid(pid_, &st, 0);
  }
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

bool Process::running() {
  if (status_) return false;
  int st = 0;
  const pid_t r = ::waitpid(pid_, &st, WNOHANG);
  if (r == pid_) {
    status_ = st;
    return false;
  }
  return r == 0;
}

void Process::signal(int sig) {
  if (running()) ::kill(pid_, sig);
}

ProcessResult Process::wait(std::chrono::milliseconds timeout) {
  ProcessResult r;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid_, SIGKILL);
      int st = 0;
      ::waitpid(pid_, &st, 0);
      status_ = st;
      r.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (status_) {
    if (WIFEXITED(*status_)) r.exit_code = WEXITSTATUS(*status_);
    if (WIFSIGNALED(*status_)) r.exit_code = 128 + WTERMSIG(*status_);
  }
  r.out = out_so_far();
  r.err = err_so_far();
  return r;
}

std::string Process::out_so_far() const {
  return slurp(dir_ / "out");
}
std::string Process::err_so_far() const {
  return slurp(dir_ / "err");
}

ProcessResult run(std::vector<std::string> argv, std::chrono::milliseconds timeout) {
  Process p(std::move(argv));
  return p.wait(timeout);
}

TempDir::TempDir() : path_(make_temp_dir("tactile-test-")) {}
TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

bool realtime_allowed(int priority, bool lock) {
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    sched_param p{};
    p.sched_priority = priority;
    const bool ok = ::sched_setscheduler(0, SCHED_FIFO, &p) == 0 &&
                    (!lock || ::mlockall(MCL_CURRENT | MCL_FUTURE) == 0);
    ::_exit(ok ? 0 : 1);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

std::vector<ThreadScheduling> thread_scheduling(pid_t pid) {
  std::vector<ThreadScheduling> out;
  for (const auto& t :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task")) {
    std::ifstream in(t.path() / "stat");
    const std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // Fields 40 (rt_priority) and 41 (policy), counted after the command name, which may hold
    // spaces and ends at the last ')'.
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));
    const std::vector<std::string> f{std::istream_iterator<std::string>(fields), {}};
    ThreadScheduling s;
    std::ifstream(t.path() / "comm") >> s.name;
    if (f.size() > 38) {
      s.policy = std::stoi(f[38]);
      s.priority = std::stoi(f[37]);
    }
    out.push_back(s);
  }
  return out;
}

std::string realtime_log_line(int priority, bool lock) {
  return "real-time scheduling: SCHED_FIFO priority " + std::to_string(priority) +
         (lock ? ", memory locked" : "");
}

}  // namespace tactile::testing
