#include "process.hpp"

#include <sched.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

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
  util::ProcessOptions o;
  o.argv = std::move(argv);
  o.extra_env = std::move(extra_env);
  o.stdin_from = util::Redirect::null();
  o.stdout_to = util::Redirect::file(dir_ / "out");
  o.stderr_to = util::Redirect::file(dir_ / "err");
  try {
    process_.emplace(std::move(o));
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
    throw;
  }
}

Process::~Process() {
  process_.reset();  // kills (SIGKILL) a process still running
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

ProcessResult Process::wait(std::chrono::milliseconds timeout) {
  ProcessResult r;
  std::optional<int> status = process_->wait_for(timeout);
  if (!status) {
    status = process_->kill();
    r.timed_out = true;
  }
  r.exit_code = *status;
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
