#include "tactile/util/process.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using tactile::util::Process;
using tactile::util::ProcessOptions;
using tactile::util::Redirect;

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

ProcessOptions program(std::vector<std::string> argv) {
  ProcessOptions o;
  o.argv = std::move(argv);
  return o;
}

ProcessOptions shell(const std::string& script) {
  return program({"sh", "-c", script});  // found in PATH
}

// The state letter of /proc/PID/stat ('Z' for a zombie), or 0 when the process is gone.
char state_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  if (!std::getline(in, stat)) return 0;
  return stat[stat.rfind(')') + 2];
}

TEST(Process, WritesEachStreamToItsFileAndGivesTheExitCode) {
  tactile::testing::TempDir dir;
  ProcessOptions o = shell("echo out; echo err >&2; read x || echo no-input; exit 3");
  o.stdin_from = Redirect::null();
  o.stdout_to = Redirect::file(dir / "out");
  o.stderr_to = Redirect::file(dir / "err");
  Process p(std::move(o));
  EXPECT_EQ(p.wait_for(milliseconds(10000)), 3);
  EXPECT_EQ(p.exit_status(), 3);
  EXPECT_FALSE(p.running());
  EXPECT_EQ(read(dir / "out"), "out\nno-input\n");
  EXPECT_EQ(read(dir / "err"), "err\n");
}

TEST(Process, AppendsToALogAndSendsStandardErrorWhereStandardOutputGoes) {
  tactile::testing::TempDir dir;
  std::ofstream(dir / "log") << "before\n";
  ProcessOptions o = shell("echo out; echo err >&2");
  o.stdout_to = Redirect::append(dir / "log");
  o.stderr_to = Redirect::standard_output();
  Process p(std::move(o));
  EXPECT_EQ(p.wait_for(milliseconds(10000)), 0);
  EXPECT_EQ(read(dir / "log"), "before\nout\nerr\n");
}

TEST(Process, ReadsAPipeAndAddsToTheEnvironment) {
  ProcessOptions o = shell("echo \"$TACTILE_PROCESS_TEST\"; echo err >&2; echo \"${HOME:+home}\"");
  o.extra_env = {"TACTILE_PROCESS_TEST=given"};
  o.stdout_to = Redirect::pipe();
  o.stderr_to = Redirect::standard_output();
  Process p(std::move(o));
  EXPECT_EQ(p.wait_for(milliseconds(10000)), 0);
  // The rest of the environment stays (HOME is set wherever the tests run).
  EXPECT_EQ(p.output(), "given\nerr\n" + std::string(std::getenv("HOME") ? "home\n" : "\n"));
}

TEST(Process, AProgramThatCannotStartThrowsNamingIt) {
  try {
    Process p(program({"/nonexistent/tactile-no-such-program"}));
    FAIL() << "started";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "cannot start /nonexistent/tactile-no-such-program: No such file or directory");
  }
  EXPECT_THROW(Process(program({"tactile-no-such-program-in-path"})), std::runtime_error);
  ProcessOptions unwritable = shell("true");
  unwritable.stdout_to = Redirect::file("/nonexistent/dir/out");
  EXPECT_THROW(Process{std::move(unwritable)}, std::runtime_error);
  EXPECT_THROW(Process(ProcessOptions{}), std::invalid_argument);
  ProcessOptions piped_input = shell("true");
  piped_input.stdin_from = Redirect::pipe();
  EXPECT_THROW(Process{std::move(piped_input)}, std::invalid_argument);
}

TEST(Process, WaitGivesUpAtItsDeadlineAndStopSendsTheStopSignal) {
  ProcessOptions o = program({"sleep", "30"});
  o.stop_signal = SIGINT;
  Process p(std::move(o));
  EXPECT_EQ(p.wait_for(milliseconds(50)), std::nullopt);
  EXPECT_TRUE(p.running());
  EXPECT_EQ(p.stop(milliseconds(10000)), 128 + SIGINT);
  EXPECT_EQ(p.exit_status(), 128 + SIGINT);
}

TEST(Process, StopKillsAProcessThatIgnoresTheSignalAfterTheGrace) {
  // The script says it is ready once its trap is set, so the signal cannot come before it.
  ProcessOptions o = shell("trap '' TERM; echo ready; while :; do sleep 0.05; done");
  o.stdout_to = Redirect::pipe();
  Process p(std::move(o));
  while (p.output().empty() && p.running())
    p.wait_for(milliseconds(20));
  ASSERT_EQ(p.output(), "ready\n");
  EXPECT_EQ(p.stop(milliseconds(100)), 128 + SIGKILL);
}

TEST(Process, TheDestructorKillsAProcessStillRunning) {
  pid_t pid = 0;
  {
    Process p(program({"sleep", "30"}));
    pid = p.pid();
    EXPECT_NE(state_of(pid), 0);
  }
  EXPECT_EQ(state_of(pid), 0);  // killed and reaped
}

TEST(Process, TheDestructorGivesTheGraceAskedFor) {
  tactile::testing::TempDir dir;
  ProcessOptions o =
      shell("trap 'echo stopped; exit 5' TERM; echo ready; while :; do sleep 0.05; done");
  o.stdout_to = Redirect::file(dir / "out");
  o.destroy_grace = milliseconds(10000);
  {
    Process p(std::move(o));
    while (read(dir / "out").empty() && p.running())
      p.wait_for(milliseconds(20));
  }
  EXPECT_EQ(read(dir / "out"), "ready\nstopped\n");
}

TEST(Process, AnOwnProcessGroupOnlyWhenAsked) {
  ProcessOptions own = program({"sleep", "30"});
  own.own_process_group = true;
  Process a(std::move(own));
  Process b(program({"sleep", "30"}));
  EXPECT_EQ(::getpgid(a.pid()), a.pid());
  EXPECT_EQ(::getpgid(b.pid()), ::getpgrp());
}

TEST(Process, AChildDiesWithTheProcessThatStartedIt) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t middle = ::fork();
  ASSERT_GE(middle, 0);
  if (middle == 0) {
    // Starts a child, tells its pid and ends without the destructor's kill.
    Process p(program({"sleep", "30"}));
    const pid_t pid = p.pid();
    (void)!::write(fds[1], &pid, sizeof pid);
    ::_exit(0);
  }
  ::close(fds[1]);
  pid_t child = 0;
  ASSERT_EQ(::read(fds[0], &child, sizeof child), static_cast<ssize_t>(sizeof child));
  ::close(fds[0]);
  int raw = 0;
  ::waitpid(middle, &raw, 0);
  // The kernel's SIGKILL is immediate; whoever reaps the orphan may take a moment.
  char state = state_of(child);
  for (int i = 0; i < 500 && state != 0 && state != 'Z'; ++i) {
    ::usleep(10000);
    state = state_of(child);
  }
  EXPECT_TRUE(state == 0 || state == 'Z') << state;
}

TEST(Process, MovesWithoutStoppingTheChild) {
  Process a(program({"sleep", "30"}));
  const pid_t pid = a.pid();
  Process b(std::move(a));
  EXPECT_EQ(b.pid(), pid);
  EXPECT_TRUE(b.running());
  EXPECT_EQ(b.kill(), 128 + SIGKILL);
}

}  // namespace
