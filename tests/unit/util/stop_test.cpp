// util::install_stop_handlers in a real child process (fork): the first SIGINT or SIGTERM asks for
// a clean stop, a second one while the child is still stopping ends it at once with 128 + its
// number (docs/reliability.md#signals).
#include "tactile/util/stop.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <optional>
#include <thread>

#include "tactile/util/process.hpp"

namespace {

enum class AfterStop { kExitWithInterruptedStatus, kHang };

// A child that installs the handlers, says 'r', waits for the stop, says 's' and then either exits
// with util::interrupted_exit_status() or hangs as a program stuck in its clean-up would.
class Child {
 public:
  explicit Child(AfterStop after) {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error("pipe");
    pid_ = fork();
    if (pid_ == 0) {
      close(fds[0]);
      tactile::util::install_stop_handlers();
      (void)!write(fds[1], "r", 1);
      while (!tactile::util::stop_requested())
        usleep(1000);
      (void)!write(fds[1], "s", 1);
      if (after == AfterStop::kExitWithInterruptedStatus)
        _exit(tactile::util::interrupted_exit_status());
      for (;;)
        pause();
    }
    close(fds[1]);
    fd_ = fds[0];
  }
  ~Child() {
    if (pid_ > 0 && !status_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(fd_);
  }
  // The next byte the child says, waiting at most 10 s (0: none).
  char said() {
    pollfd p{fd_, POLLIN, 0};
    char c = 0;
    if (poll(&p, 1, 10000) == 1 && read(fd_, &c, 1) == 1) return c;
    return 0;
  }
  void signal(int sig) { kill(pid_, sig); }
  // Its exit status (128 + a signal that killed it), or nothing within `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    int raw = 0;
    while (std::chrono::steady_clock::now() < end) {
      if (waitpid(pid_, &raw, WNOHANG) == pid_) {
        status_ = tactile::util::exit_status_of(raw);
        return status_;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return std::nullopt;
  }

 private:
  pid_t pid_ = -1;
  int fd_ = -1;
  std::optional<int> status_;
};

TEST(StopHandlers, OneSignalAsksForACleanStopAndNamesTheSignal) {
  for (const int sig : {SIGINT, SIGTERM}) {
    Child child(AfterStop::kExitWithInterruptedStatus);
    ASSERT_EQ(child.said(), 'r');
    child.signal(sig);
    EXPECT_EQ(child.said(), 's') << "the flag is set, the child goes on to its clean end";
    EXPECT_EQ(child.wait(std::chrono::seconds(10)), 128 + sig);
  }
}

TEST(StopHandlers, ASecondSignalWhileStoppingEndsAtOnceWith128PlusItsNumber) {
  for (const int first : {SIGINT, SIGTERM}) {
    for (const int second : {SIGINT, SIGTERM}) {
      Child child(AfterStop::kHang);
      ASSERT_EQ(child.said(), 'r');
      child.signal(first);
      ASSERT_EQ(child.said(), 's');
      EXPECT_FALSE(child.wait(std::chrono::milliseconds(50))) << "stuck in its clean-up";
      child.signal(second);
      EXPECT_EQ(child.wait(std::chrono::seconds(5)), 128 + second)
          << "first " << first << ", second " << second;
    }
  }
}

TEST(StopHandlers, NoSignalNoInterruptedStatus) {
  EXPECT_EQ(tactile::util::stop_signal(), 0);
  EXPECT_EQ(tactile::util::interrupted_exit_status(), 0);
}

}  // namespace
