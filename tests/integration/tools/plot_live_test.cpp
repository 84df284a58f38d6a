// tactile_plot on a log it reads from a real file, and tactile_live against real publishers, in
// line mode (a pipe) and in screen mode (a pseudo-terminal).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include "tactile/recording/log_writer.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "test_log.hpp"
#include "tools_support.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using testing::Process;
using testing::TempDir;
using tools_test::await_match;
using tools_test::fill_frame;
using tools_test::write_test_log;

bool is_png(const std::filesystem::path& p) {
  std::error_code ec;
  if (!std::filesystem::exists(p, ec)) return false;
  const std::string b = util::read_file(p);
  return b.size() > 1000 && b.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}

// A PNG's width and height (its IHDR chunk, big-endian, right after the signature).
std::pair<std::uint32_t, std::uint32_t> png_size(const std::filesystem::path& p) {
  const std::string b = util::read_file(p);
  const auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i)
      v = (v << 8) | static_cast<std::uint8_t>(b.at(at + i));
    return v;
  };
  return {be32(16), be32(20)};
}

TEST(Plot, DrawsEveryFigureFromALog) {
  TempDir dir;
  write_test_log(dir / "run.tlog", true);
  const auto r = testing::run({TACTILE_PLOT_PATH, (dir / "run.tlog").string(), "-o",
                               (dir / "out").string(), "--at", "0.2", "--at", "0.9"},
                              60s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Fig. 10 fingertip x: GroundTruth object_position_m"), std::string::npos)
      << r.out;
  for (const char* name : {"shear_left.png", "shear_right.png", "fig10.png", "forces_left.png",
                           "forces_right.png", "timeline.png", "latency.png"}) {
    EXPECT_TRUE(is_png(dir / "out" / name)) << name;
    EXPECT_NE(r.out.find(std::string("wrote ") + (dir / "out" / name).string()), std::string::npos)
        << r.out;
  }
  // The fingertip (a ring of elements, as wide as tall) fills each snapshot's panel to scale:
  // the picture is about two squares tall, not 1000 x 700 with the ring in a fifth of each axis.
  const auto [width, height] = png_size(dir / "out" / "shear_left.png");
  EXPECT_EQ(width, 1000U);
  EXPECT_GT(height, 2 * 850U);
}

TEST(Plot, WithoutPositionsFig10IsAgainstTimeAndSaysSo) {
  TempDir dir;
  write_test_log(dir / "run.tlog", false);
  const auto r = testing::run({TACTILE_PLOT_PATH, (dir / "run.tlog").string(), "-o",
                               (dir / "out").string(), "--figure", "fig10", "--sensor", "right"},
                              60s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Fig. 10 fingertip x: none in the log"), std::string::npos) << r.out;
  EXPECT_TRUE(is_png(dir / "out" / "fig10.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "timeline.png"));
}

// The flags drawn are hand_node's, and the program says who decided them: hand_node's detector,
// nobody (a log without Decisions), or the detector --recompute names.
TEST(Plot, SaysWhoDecidedTheFlags) {
  TempDir dir;
  write_test_log(dir / "decided.tlog", false, true, true);
  write_test_log(dir / "frames.tlog", false);
  const auto plot = [&](const std::string& log, std::vector<std::string> extra) {
    std::vector<std::string> argv{TACTILE_PLOT_PATH,      (dir / log).string(), "-o",
                                  (dir / "out").string(), "--figure",           "timeline"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    const auto r = testing::run(argv, 60s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.out;
  };
  EXPECT_NE(plot("decided.tlog", {}).find("flags: hand_node (learned)\n"), std::string::npos);
  EXPECT_NE(plot("frames.tlog", {}).find("no hand_node decisions in the log: no flags"),
            std::string::npos);
  EXPECT_NE(plot("decided.tlog", {"--recompute", "field"}).find("flags: recomputed (field)\n"),
            std::string::npos);
  const auto r =
      testing::run({TACTILE_PLOT_PATH, (dir / "frames.tlog").string(), "--recompute", "papers"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("must be paper, field or learned"), std::string::npos) << r.err;
}

// --calibration as --help shows it, once per file, and as a list after one flag: both read both
// files (here missing: the first is named) and keep the last argument for the log.
TEST(Plot, CalibrationFilesOncePerFlagOrAsAList) {
  TempDir dir;
  write_test_log(dir / "run.tlog", false);
  const std::string a = (dir / "a.yaml").string();
  const std::string b = (dir / "b.yaml").string();
  for (const auto& argv :
       {std::vector<std::string>{TACTILE_PLOT_PATH, "--calibration", a, "--calibration", b,
                                 (dir / "run.tlog").string()},
        std::vector<std::string>{TACTILE_PLOT_PATH, "--calibration", a, b,
                                 (dir / "run.tlog").string()}}) {
    const auto r = testing::run(argv);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(a), std::string::npos) << r.err;
  }
  const auto help = testing::run({TACTILE_PLOT_PATH, "--help"});
  EXPECT_NE(help.out.find("--calibration FILE "), std::string::npos) << help.out;
}

TEST(Plot, AtPastTheEndIsAnErrorNamingTheRecordingsTimeRange) {
  TempDir dir;
  write_test_log(dir / "run.tlog", true);
  const auto r = testing::run({TACTILE_PLOT_PATH, (dir / "run.tlog").string(), "-o",
                               (dir / "out").string(), "--at", "0.5", "--at", "999"},
                              60s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  // 100 frames 10 ms apart, the first 0.5 ms after the log's first record.
  EXPECT_NE(r.err.find("--at 999: past the end of"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0.001 to 0.991 s"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "shear_left.png"));
}

TEST(Plot, BadInputGivesOneClearLine) {
  TempDir dir;
  write_test_log(dir / "empty.tlog", true, false);
  auto r =
      testing::run({TACTILE_PLOT_PATH, (dir / "empty.tlog").string(), "-o", (dir / "o").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("empty.tlog: no TactileFrames"), std::string::npos) << r.err;
  r = testing::run({TACTILE_PLOT_PATH, (dir / "missing.tlog").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.tlog: cannot open"), std::string::npos) << r.err;
  r = testing::run({TACTILE_PLOT_PATH, (dir / "empty.tlog").string(), "--figure", "pie"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--figure must be"), std::string::npos) << r.err;
  r = testing::run({TACTILE_PLOT_PATH});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const char* tool : {TACTILE_PLOT_PATH, TACTILE_LIVE_PATH}) {
    r = testing::run({tool, "--help"});
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("Usage"), std::string::npos);
  }
  r = testing::run({TACTILE_LIVE_PATH});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tactile_live: give at least one endpoint"), std::string::npos);
}

// Publishes frames of two fingertips on one endpoint and events on another until `done`.
template <typename Done>
void publish_until(wire::Publisher& frames, wire::Publisher& events, Done done) {
  v1::Envelope env;
  std::string buf;
  std::uint64_t k = 0;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (!done() && std::chrono::steady_clock::now() < deadline) {
    for (const char* id : {"left", "right"}) {
      fill_frame(*env.mutable_tactile_frame(), id, k, util::realtime_ns());
      wire::encode(env, buf);
      frames.send(wire::frame_topic(id), wire::bytes_of(buf));
    }
    if (k % 20 == 0) {
      auto* e = env.mutable_event();
      e->Clear();
      e->set_time_ns(util::realtime_ns());
      e->set_kind(v1::EVENT_KIND_RECOMPRESS);
      e->set_phase("TRANSPORT");
      e->set_sensor_id("left");
      e->set_element_id(4);
      e->set_text("re-compress");
      wire::encode(env, buf);
      events.send(wire::kEventTopic, wire::bytes_of(buf));
      // hand_node's decision on this frame: element 4 of the left fingertip slips.
      auto* d = env.mutable_decision();
      d->Clear();
      d->set_slip_detector("learned");
      auto* t = d->add_fingertips();
      t->set_sensor_id("left");
      t->set_slip(true);
      t->set_touch(true);
      t->add_slipping_element_ids(4);
      wire::encode(env, buf);
      events.send(wire::kDecisionTopic, wire::bytes_of(buf));
    }
    ++k;
    std::this_thread::sleep_for(5ms);
  }
}

TEST(Live, LineModeFollowsRealPublishers) {
  zmq::context_t ctx;
  wire::Publisher frames(ctx, "tcp://127.0.0.1:*");
  wire::Publisher events(ctx, "tcp://127.0.0.1:*");
  Process live({TACTILE_LIVE_PATH, frames.endpoint(), events.endpoint(), "--interval", "0.1"});
  publish_until(frames, events, [&] {
    const std::string out = live.out_so_far();
    return out.find("right seq=") != std::string::npos &&
           out.find("RECOMPRESS left e4 re-compress") != std::string::npos &&
           out.find("phase=TRANSPORT") != std::string::npos &&
           out.find("by=hand_node") != std::string::npos;
  });
  live.signal(SIGINT);
  const auto r = live.wait(10s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("right seq="), std::string::npos) << r.out;
  EXPECT_TRUE(std::regex_search(r.out, std::regex("left seq=\\d+ fps=\\d+\\.\\d lost=0 "
                                                  "status=COMPLETE contact=11/41 ")))
      << r.out;
  EXPECT_NE(r.out.find("event "), std::string::npos);
  EXPECT_NE(r.out.find("RECOMPRESS left e4 re-compress"), std::string::npos) << r.out;
  // hand_node's decisions come on its events endpoint, topic decision: shown as decided there.
  EXPECT_TRUE(std::regex_search(r.out, std::regex("left seq=\\d+ .* flags=TOUCH,SLIP slipping=4 "
                                                  "by=hand_node detector=learned ")))
      << r.out;
  EXPECT_EQ(r.out.find("\x1b"), std::string::npos);  // no escape codes into a pipe
}

TEST(Live, AnEndpointSilentForTheSilenceTimeoutEndsItNonZeroNamingThatEndpoint) {
  zmq::context_t ctx;
  wire::Publisher frames(ctx, "tcp://127.0.0.1:*");
  wire::Publisher events(ctx, "tcp://127.0.0.1:*");
  wire::Publisher silent(ctx, "tcp://127.0.0.1:*");
  const auto start = std::chrono::steady_clock::now();
  Process live({TACTILE_LIVE_PATH, frames.endpoint(), events.endpoint(), silent.endpoint(),
                "--silence-timeout", "1", "--interval", "0.1"});
  publish_until(frames, events, [&] { return !live.running(); });
  const auto r = live.wait(10s);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_GE(elapsed, 1s);
  EXPECT_LT(elapsed, 8s);  // the timeout and a margin for a loaded machine
  EXPECT_EQ(r.err, "tactile_live: nothing heard from " + silent.endpoint() + " within 1 s\n");
  EXPECT_NE(r.out.find("left seq="), std::string::npos) << r.out;  // it showed what it heard
}

// Runs tactile_live on a pseudo-terminal (TERM=xterm) and collects what it draws.
class PtyProcess {
 public:
  explicit PtyProcess(std::vector<std::string> argv) {
    master_ = posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0)
      throw std::runtime_error("pty");
    const std::string slave = ptsname(master_);
    winsize ws{};
    ws.ws_col = 100;
    ws.ws_row = 40;
    ioctl(master_, TIOCSWINSZ, &ws);
    const pid_t parent = getpid();
    pid_ = fork();
    if (pid_ == 0) {
      setsid();
      // A session of its own, so the test's terminal signals miss it: it dies with the test
      // instead, even a test killed by SIGKILL (docs/reliability.md, "What a killed run leaves").
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(127);
      const int s = open(slave.c_str(), O_RDWR);
      dup2(s, 0);
      dup2(s, 1);
      const int devnull = open("/dev/null", O_WRONLY);
      dup2(devnull, 2);
      setenv("TERM", "xterm", 1);
      std::vector<char*> args;
      for (auto& a : argv)
        args.push_back(a.data());
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    fcntl(master_, F_SETFL, O_NONBLOCK);
  }
  // What it drew, without escape sequences.
  std::string text() {
    const std::string& raw = read();
    std::string t;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] == '\x1b') {
        while (i < raw.size() && std::isalpha(static_cast<unsigned char>(raw[i])) == 0)
          ++i;
        continue;
      }
      t += raw[i];
    }
    return t;
  }
  ~PtyProcess() {
    if (pid_ > 0 && waitpid(pid_, nullptr, WNOHANG) == 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(master_);
  }
  const std::string& read() {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n <= 0) break;
      out_.append(buf, static_cast<std::size_t>(n));
    }
    return out_;
  }
  int stop(int sig) {
    kill(pid_, sig);
    int st = 0;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (waitpid(pid_, &st, WNOHANG) == 0) {
      read();
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &st, 0);
        return -1;
      }
      std::this_thread::sleep_for(5ms);
    }
    read();
    pid_ = -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }

 private:
  int master_ = -1;
  pid_t pid_ = -1;
  std::string out_;
};

TEST(Live, ScreenModeOnATerminalDrawsTheDomeAndRestoresTheTerminal) {
  zmq::context_t ctx;
  wire::Publisher frames(ctx, "tcp://127.0.0.1:*");
  wire::Publisher events(ctx, "tcp://127.0.0.1:*");
  PtyProcess live({TACTILE_LIVE_PATH, frames.endpoint(), events.endpoint()});
  publish_until(frames, events, [&] {
    const std::string t = live.text();
    return t.find("right seq") != std::string::npos && t.find("RECOMPRESS") != std::string::npos;
  });
  const int code = live.stop(SIGTERM);
  EXPECT_EQ(code, 0);
  const std::string& out = live.read();
  EXPECT_EQ(out.rfind("\x1b[?1049h", 0), 0U);  // the alternate screen first
  EXPECT_NE(out.find("\x1b[H"), std::string::npos);
  EXPECT_NE(live.text().find("left seq"), std::string::npos);
  EXPECT_NE(out.find("\x1b[32m"), std::string::npos);  // force digits in colour
  const auto restore = out.rfind("\x1b[?25h\x1b[?1049l");
  ASSERT_NE(restore, std::string::npos);
  EXPECT_EQ(restore + std::string("\x1b[?25h\x1b[?1049l").size(), out.size());
  // Redrawn at least 10 times a second: count the frames drawn while it ran.
  std::size_t frames_drawn = 0;
  for (auto at = out.find("\x1b[H"); at != std::string::npos; at = out.find("\x1b[H", at + 1))
    ++frames_drawn;
  EXPECT_GE(frames_drawn, 2U);
}

}  // namespace
}  // namespace tactile
