// The latency benchmark's analysis on a recorded capture (tests/data/latency/capture.tlog, which
// make_latency_capture writes; its header comment gives the run). Every figure below follows
// from those latencies by hand; percentiles are nearest rank.
#include "latency_analysis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "process.hpp"
#include "recorded_capture.hpp"

namespace {

namespace fs = std::filesystem;
using tactile::bench::Captured;
using tactile::bench::PipelineResult;

using tactile::bench::testing::kT0;
const fs::path kCapture = tactile::bench::testing::recorded_capture();

PipelineResult analysed() {
  return tactile::bench::testing::recorded_analysis();
}

TEST(LatencyCapture, ReadsEveryRecordedMessage) {
  const std::vector<Captured> cap = tactile::bench::read_capture(kCapture);
  // 30 truths, 59 frames, 28 decisions and commands, 1 event.
  ASSERT_EQ(cap.size(), 30U + 59U + 28U + 28U + 1U);
  EXPECT_EQ(cap.front().topic, "truth");
  EXPECT_EQ(cap.front().receive_ns, kT0 + 100'000);
  EXPECT_EQ(cap[1].topic, "frame/left");
}

TEST(LatencyCapture, TheFileIsWhatTheGeneratorWrites) {
  tactile::testing::TempDir dir;
  const tactile::testing::ProcessResult r =
      tactile::testing::run({TACTILE_MAKE_LATENCY_CAPTURE, (dir / "capture.tlog").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<Captured> a = tactile::bench::read_capture(kCapture);
  const std::vector<Captured> b = tactile::bench::read_capture(dir / "capture.tlog");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].receive_ns, b[i].receive_ns) << i;
    EXPECT_EQ(a[i].topic, b[i].topic) << i;
    EXPECT_EQ(a[i].payload, b[i].payload) << i;
  }
}

TEST(LatencyAnalysis, CountsTheWindowsFramesGapsAndStatuses) {
  const PipelineResult r = analysed();
  EXPECT_EQ(r.frames, 39U);  // 20 left, 19 right (k = 12 missed)
  EXPECT_EQ(r.frames_complete, 38U);
  EXPECT_EQ(r.frames_incomplete, 1U);
  EXPECT_EQ(r.sequence_gaps, 1U);
  ASSERT_EQ(r.incomplete_run.size(), 1U);
  EXPECT_EQ(r.incomplete_run[0]["sequence"], 21);
  EXPECT_EQ(r.incomplete_run[0]["status"], "FRAME_STATUS_MISSING_PACKETS");
  EXPECT_GT(r.frame_bytes_p50, 0U);
  EXPECT_GT(r.command_bytes_p50, 0U);
}

TEST(LatencyAnalysis, FrameStagesAreNearestRankOfTheWholeFrames) {
  const PipelineResult r = analysed();
  // 19 left frames, 1.05..1.24 ms without 1.20, and 19 right at 1.5 ms: rank 19 of 38 is the
  // largest left one.
  EXPECT_EQ(r.gige.n, 38U);
  EXPECT_NEAR(r.gige.p50, 1.24, 1e-9);
  EXPECT_NEAR(r.gige.p99, 1.5, 1e-9);
  EXPECT_NEAR(r.gige.max, 1.5, 1e-9);
  // The later of each exposure both cameras delivered whole: 18 exposures, right's 1.5 ms.
  EXPECT_EQ(r.gige_pair.n, 18U);
  EXPECT_NEAR(r.gige_pair.p50, 1.5, 1e-9);
  EXPECT_EQ(r.gige_negative, 0U);
  EXPECT_NEAR(r.measure.p50, 0.3, 1e-9);
  EXPECT_NEAR(r.measure_core.max, 0.2, 1e-9);
  // Gaps: 20 ms where a frame is missing, under the staleness limit of 30 ms.
  EXPECT_NEAR(r.max_camera_gap_ms, 20.0, 1e-9);
  EXPECT_NEAR(r.max_publish_gap_ms, 20.02, 1e-9);
  EXPECT_EQ(r.camera_gaps_over_stale, 0U);
  EXPECT_EQ(r.publish_gaps_over_stale, 0U);
}

TEST(LatencyAnalysis, CommandAndDecisionStages) {
  const PipelineResult r = analysed();
  EXPECT_EQ(r.commands, 18U);
  EXPECT_EQ(r.command_kinds.at("move_to"), 17U);
  EXPECT_EQ(r.command_kinds.at("hold"), 1U);
  EXPECT_EQ(r.pub_recv.n, 36U);
  EXPECT_NEAR(r.pub_recv.p50, 0.1, 1e-9);
  EXPECT_NEAR(r.control.p99, 0.04, 1e-9);
  EXPECT_NEAR(r.cam_to_send_fresh.p50, 1.94, 1e-9);
  EXPECT_EQ(r.cam_to_send_all.n, 36U);
  EXPECT_EQ(r.cam_to_send_all_no_hold.n, 34U);
  EXPECT_EQ(r.cam_to_send_all_run.n, 56U);  // every command of the run, two answers each
  EXPECT_EQ(r.e2e.n, 56U);
  EXPECT_EQ(r.decisions, 18U);
  EXPECT_EQ(r.frames_without_decision, 2U);  // left k = 12, right k = 20: whole, unanswered
  EXPECT_EQ(r.cam_to_decision.n, 36U);
  EXPECT_NEAR(r.cam_to_decision.max, 1.93, 1e-9);
  EXPECT_NEAR(r.receive_to_decision.p50, 0.03, 1e-9);  // right's, the later frame
}

TEST(LatencyAnalysis, SlipOnsetToRecompressionAgainstTheTruth) {
  const PipelineResult r = analysed();
  EXPECT_EQ(r.true_slip_episodes, 1U);
  EXPECT_EQ(r.recompress_events, 1U);
  EXPECT_EQ(r.recompress_no_command, 0U);
  EXPECT_EQ(r.recompress_no_onset, 0U);
  // Onset at k = 15, the command answering k = 16 sent 1.94 ms after k = 16's exposure.
  ASSERT_EQ(r.slip_to_recompress_ms.size(), 1U);
  EXPECT_NEAR(r.slip_to_recompress_ms[0], 11.94, 1e-9);
  EXPECT_EQ(r.events.at("EVENT_KIND_RECOMPRESS"), 1U);
}

TEST(LatencyAnalysis, ACaptureCutShortIsRefusedNamingTheFile) {
  tactile::testing::TempDir dir;
  const fs::path cut = dir / "cut.tlog";
  fs::copy_file(kCapture, cut);
  fs::resize_file(cut, fs::file_size(cut) - 10);
  try {
    tactile::bench::read_capture(cut);
    FAIL() << "read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cut.tlog"), std::string::npos) << e.what();
  }
}

}  // namespace
