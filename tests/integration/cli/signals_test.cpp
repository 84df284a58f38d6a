// The signal convention on every long-running program, as a real process (docs/reliability.md,
// "Signals"): one SIGINT or SIGTERM ends it cleanly, with 0 where a signal is its normal end (the
// services) and 128 + the signal's number where it cut work short (a sweep, a recording with an
// end, training); a second signal while it is still stopping ends it at once with 128 + that
// signal's number.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using tactile::testing::Process;
using tactile::testing::ProcessResult;
using tactile::testing::TempDir;

const fs::path kSource = TACTILE_SOURCE_DIR;

struct LongRun {
  std::string name;
  // The command line, in a fresh folder.
  std::function<std::vector<std::string>(const TempDir&)> argv;
  std::string ready;      // a line it writes on standard error once its handlers are installed
  std::string clean_end;  // a line it writes on standard error at its clean end only
  bool signal_is_its_end = true;  // 0 on one signal; else 128 + the signal's number
  // What the clean end leaves, checked after one signal (may be empty).
  std::function<void(const TempDir&, const ProcessResult&)> check;
};

void PrintTo(const LongRun& r, std::ostream* os) {
  *os << r.name;
}

void copy_calibrations(const TempDir& dir) {
  for (const char* f : {"left.yaml", "right.yaml"})
    fs::copy_file(kSource / "docker" / "config" / f, dir / f);
}

std::vector<LongRun> long_runs() {
  std::vector<LongRun> out;
  out.push_back({"hand_node",
                 [](const TempDir& dir) {
                   copy_calibrations(dir);
                   std::ofstream(dir / "hand.yaml")
                       << "format: tactile-hand/1\n"
                          "fingertips:\n"
                          "  - {sensor_id: left, calibration: left.yaml}\n"
                          "  - {sensor_id: right, calibration: right.yaml}\n";
                   // Nobody at either end: it waits for the arm controller.
                   return std::vector<std::string>{TACTILE_HAND_NODE_PATH,
                                                   "--config",
                                                   (dir / "hand.yaml").string(),
                                                   "--subscribe",
                                                   "ipc://" + (dir / "sensors").string(),
                                                   "--arm",
                                                   "ipc://" + (dir / "arm").string()};
                 },
                 "subscribing to",
                 "stop requested: sending Stop to the arm",
                 true,
                 {}});
  out.push_back({"sensor_node",
                 [](const TempDir& dir) {
                   copy_calibrations(dir);
                   // Nothing answers on 127.0.0.201: it retries until stopped.
                   return std::vector<std::string>{TACTILE_SENSOR_NODE_PATH,
                                                   "--camera",
                                                   "127.0.0.201",
                                                   "--calibration",
                                                   (dir / "left.yaml").string(),
                                                   "--publish",
                                                   "ipc://" + (dir / "frames").string()};
                 },
                 "retrying",
                 "published ",
                 true,
                 {}});
  out.push_back({"arm_bridge",
                 [](const TempDir& dir) {
                   return std::vector<std::string>{TACTILE_ARM_BRIDGE_PATH, "--endpoint",
                                                   "ipc://" + (dir / "arm").string()};
                 },
                 "arm controller on",
                 "stopped: arm held",
                 true,
                 {}});
  out.push_back({"tactile_record",
                 [](const TempDir& dir) {
                   // A recording until a signal, of a publisher that is never there.
                   return std::vector<std::string>{
                       TACTILE_RECORD_PATH,         "-o",
                       (dir / "run.tlog").string(), "ipc://" + (dir / "nobody").string(),
                       "--silence-timeout",         "0"};
                 },
                 "recording to",
                 "recorded ",
                 true,
                 {}});
  out.push_back({"tactile_record_with_duration",
                 [](const TempDir& dir) {
                   return std::vector<std::string>{TACTILE_RECORD_PATH,
                                                   "-o",
                                                   (dir / "run.tlog").string(),
                                                   "ipc://" + (dir / "nobody").string(),
                                                   "--silence-timeout",
                                                   "0",
                                                   "--duration",
                                                   "60"};
                 },
                 "recording to", "recorded ", false,
                 [](const TempDir& dir, const ProcessResult& r) {
                   // Cut short before anything came: no header-only log is left.
                   EXPECT_FALSE(fs::exists(dir / "run.tlog")) << r.err;
                 }});
  out.push_back({"rig_sweep",
                 [](const TempDir& dir) {
                   return std::vector<std::string>{
                       TACTILE_RIG_PATH,        "--sweep", "40",          "--jobs", "1",
                       "--max-sim-time",        "6",       "--detectors", "paper",  "--out",
                       (dir / "sweep").string()};
                 },
                 "1/40 runs done", "sweep: stopped; ", false,
                 [](const TempDir& dir, const ProcessResult& r) {
                   EXPECT_TRUE(fs::exists(dir / "sweep" / "sweep.csv")) << r.err;
                   EXPECT_NE(r.err.find("sweep: stopped; "), std::string::npos) << r.err;
                 }});
  out.push_back({"slip_train",
                 [](const TempDir& dir) {
                   return std::vector<std::string>{TACTILE_SLIP_TRAIN_PATH,
                                                   "--seeds",
                                                   "1",
                                                   "--scenarios",
                                                   "40",
                                                   "--jobs",
                                                   "1",
                                                   "--max-time",
                                                   "6",
                                                   "--out",
                                                   (dir / "model.inc").string()};
                 },
                 "slip_train: run 1/40", "slip_train: stopped before training", false,
                 [](const TempDir& dir, const ProcessResult& r) {
                   EXPECT_FALSE(fs::exists(dir / "model.inc")) << r.err;
                   EXPECT_NE(r.err.find("slip_train: stopped before training: nothing written"),
                             std::string::npos)
                       << r.err;
                 }});
  return out;
}

std::string test_name(const ::testing::TestParamInfo<LongRun>& info) {
  return info.param.name;
}

class Signals : public ::testing::TestWithParam<LongRun> {
 protected:
  // Starts the program in `dir` and waits until it says it is ready.
  Process& start(const TempDir& dir) {
    proc_.emplace(GetParam().argv(dir));
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (proc_->err_so_far().find(GetParam().ready) == std::string::npos &&
           std::chrono::steady_clock::now() < deadline && proc_->running()) {
      std::this_thread::sleep_for(10ms);
    }
    EXPECT_NE(proc_->err_so_far().find(GetParam().ready), std::string::npos) << proc_->err_so_far();
    return *proc_;
  }
  std::optional<Process> proc_;
};

TEST_P(Signals, OneSignalEndsItCleanlyWithItsDocumentedStatus) {
  for (const int sig : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(sig);
    const TempDir dir;
    Process& p = start(dir);
    p.signal(sig);
    const ProcessResult r = p.wait(20s);
    ASSERT_FALSE(r.timed_out) << r.err;
    EXPECT_EQ(r.exit_code, GetParam().signal_is_its_end ? 0 : 128 + sig) << r.err;
    EXPECT_NE(r.err.find(GetParam().clean_end), std::string::npos) << r.err;
    if (GetParam().check) GetParam().check(dir, r);
    proc_.reset();
  }
}

// Both signals arrive while it is stopped (SIGSTOP), so that the second comes before the clean
// end can: the first handler to run asks for the stop, the second ends it at once with 128 + its
// own number (Linux sets up both handlers' frames before the process runs again, and which runs
// first is the kernel's business: 130 or 143), never through the clean end.
TEST_P(Signals, ASecondSignalEndsItAtOnceWith128PlusItsNumber) {
  const TempDir dir;
  Process& p = start(dir);
  p.signal(SIGSTOP);
  p.signal(SIGINT);
  p.signal(SIGTERM);
  const auto sent = std::chrono::steady_clock::now();
  p.signal(SIGCONT);
  const ProcessResult r = p.wait(10s);
  ASSERT_FALSE(r.timed_out) << r.err;
  EXPECT_TRUE(r.exit_code == 130 || r.exit_code == 143) << r.exit_code << "\n" << r.err;
  EXPECT_EQ(r.err.find(GetParam().clean_end), std::string::npos) << r.err;
  EXPECT_LT(std::chrono::steady_clock::now() - sent, 2s) << r.err;
}

INSTANTIATE_TEST_SUITE_P(LongRunning, Signals, ::testing::ValuesIn(long_runs()), test_name);

}  // namespace
