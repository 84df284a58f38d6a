#pragma once

// What every packet-loss run must show, whatever the loss: shared by the quick tests and the
// slow sweep.
#include <gtest/gtest.h>

#include "fault_support.hpp"

namespace tactile::faults {

inline void expect_loss_handled(const LossRun& run) {
  const TruthReport& t = run.truth;
  ASSERT_TRUE(run.problem.empty()) << describe(run);
  EXPECT_EQ(run.exit_status, 0) << describe(run);
  // Every frame as the truth says: incomplete ones carry their status and no readings, whole
  // ones exactly the true image's readings, displacement only across consecutive whole frames.
  EXPECT_TRUE(t.failures.empty()) << describe(run);
  EXPECT_EQ(t.displacements_after_gap, 0U) << describe(run);
  // The loss did happen, and both kinds of whole frame were seen: after a gap (displacement
  // must restart) and after a whole frame (displacement measured).
  EXPECT_GT(t.complete, 0U) << describe(run);
  EXPECT_GT(t.incomplete, 0U) << describe(run);
  EXPECT_GT(t.complete_after_gap, 0U) << describe(run);
  EXPECT_GT(t.complete_after_complete, 0U) << describe(run);
  EXPECT_GT(t.displacements_measured, 0U) << describe(run);

  // sensor_node's own account: one exit line, every received frame published, measured or not,
  // and no camera restart for mere packet loss.
  ASSERT_EQ(run.exit_lines.size(), 1U) << describe(run);
  const PublishedLine& line = run.exit_lines.front();
  EXPECT_EQ(line.published, line.measured + line.not_measured) << describe(run);
  EXPECT_GE(line.published, t.frames) << describe(run);
  EXPECT_GE(line.measured, t.complete) << describe(run);
  EXPECT_GE(line.not_measured, t.incomplete) << describe(run);
  EXPECT_EQ(line.camera_restarts, 0U) << describe(run);

  // SensorStats agree with the frames published before them (the frame sensor_node held when
  // it sent them may be counted too).
  ASSERT_FALSE(run.stats.empty()) << describe(run);
  for (const auto& seen : run.stats) {
    const v1::SensorStats& s = seen.stats;
    EXPECT_EQ(s.frames(), s.frames_complete() + s.frames_incomplete());
    EXPECT_EQ(s.camera_restarts(), 0U);
    if (t.first_seen_was_first_published) {
      EXPECT_GE(s.frames(), seen.frames_before);
      EXPECT_LE(s.frames(), seen.frames_before + 1);
    }
  }
  const v1::SensorStats& last = run.stats.back().stats;
  if (last.frames_incomplete() > 0) {
    EXPECT_GT(last.missing_packets(), 0U) << describe(run);
  }
}

}  // namespace tactile::faults
