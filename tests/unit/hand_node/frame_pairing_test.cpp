// FramePairing: the controller runs once per exposure with both fingertips fresh when their
// frames come within the window, never waits longer than the window, never for a dead sensor,
// and never lets a frame be replaced before the controller ran on it.
#include "frame_pairing.hpp"

#include <gtest/gtest.h>

namespace tactile::hand {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kWindow = 2 * kMs;
constexpr std::int64_t kPeriod = 5 * kMs;  // 200 fps

using Fresh = FramePairing::Fresh;

TEST(FramePairing, SecondFrameOfTheSameExposureRunsTheControllerWithBothFresh) {
  FramePairing p(kWindow);
  EXPECT_FALSE(p.arrived(0, 100 * kMs, 1000 * kMs, true));
  EXPECT_TRUE(p.waiting(0));
  EXPECT_EQ(p.deadline_ns(), 1000 * kMs + kWindow);
  EXPECT_FALSE(p.due(1000 * kMs + kWindow - 1));
  EXPECT_TRUE(p.arrived(1, 100 * kMs, 1000 * kMs + kMs / 4, true));
  EXPECT_EQ(p.take(), (Fresh{true, true}));
  EXPECT_FALSE(p.any_waiting());
  EXPECT_FALSE(p.due(1000 * kMs + kWindow));
}

TEST(FramePairing, EitherFingertipMayComeFirst) {
  FramePairing p(kWindow);
  for (int i = 0; i < 10; ++i) {
    const int first = i % 2;
    const std::int64_t ts = (100 + i) * kPeriod;
    EXPECT_FALSE(p.arrived(first, ts, ts + kMs, true)) << i;
    EXPECT_TRUE(p.arrived(1 - first, ts, ts + kMs + 100'000, true)) << i;
    EXPECT_EQ(p.take(), (Fresh{true, true})) << i;
  }
}

TEST(FramePairing, ALostPartnerCostsAtMostTheWindow) {
  FramePairing p(kWindow);
  EXPECT_FALSE(p.arrived(1, 100 * kMs, 1000 * kMs, true));
  EXPECT_FALSE(p.due(1000 * kMs + kWindow - 1));
  EXPECT_TRUE(p.due(1000 * kMs + kWindow));
  EXPECT_EQ(p.take(), (Fresh{false, true}));
  EXPECT_FALSE(p.due(1000 * kMs + 10 * kWindow));
}

TEST(FramePairing, APartnerFromAnotherExposureDoesNotWaitAgain) {
  FramePairing p(kWindow);
  // Fingertip 0 waits for exposure 100 ms; fingertip 1 lost it and sends exposure 105 ms.
  EXPECT_FALSE(p.arrived(0, 100 * kMs, 1000 * kMs, true));
  EXPECT_TRUE(p.arrived(1, 105 * kMs, 1001 * kMs, true));
  EXPECT_EQ(p.take(), (Fresh{true, true}));
  // Fingertip 0's frame of 105 ms comes now: its partner is already here, nothing to wait for.
  EXPECT_TRUE(p.arrived(0, 105 * kMs, 1002 * kMs, true));
  EXPECT_EQ(p.take(), (Fresh{true, false}));
}

TEST(FramePairing, ALateFrameBehindItsPartnerRunsAtOnce) {
  FramePairing p(kWindow);
  // Fingertip 1's frame of this exposure already ran alone (its partner was late).
  EXPECT_FALSE(p.arrived(1, 100 * kMs, 1000 * kMs, true));
  EXPECT_TRUE(p.due(1000 * kMs + kWindow));
  EXPECT_EQ(p.take(), (Fresh{false, true}));
  EXPECT_TRUE(p.arrived(0, 100 * kMs, 1000 * kMs + kWindow + kMs, true));
  EXPECT_EQ(p.take(), (Fresh{true, false}));
}

TEST(FramePairing, ADeadSensorIsNotWaitedFor) {
  FramePairing p(kWindow);
  EXPECT_TRUE(p.arrived(0, 100 * kMs, 1000 * kMs, false));
  EXPECT_EQ(p.take(), (Fresh{true, false}));
}

TEST(FramePairing, AFrameWaitingWhenItsNextOneComesIsReportedSoItRunsFirst) {
  FramePairing p(kWindow);
  EXPECT_FALSE(p.arrived(0, 100 * kMs, 1000 * kMs, true));
  // The caller's loop did not get to the deadline before fingertip 0's next frame: it asks.
  EXPECT_TRUE(p.waiting(0));
  EXPECT_FALSE(p.waiting(1));
  EXPECT_EQ(p.take(), (Fresh{true, false}));
  EXPECT_FALSE(p.arrived(0, 105 * kMs, 1005 * kMs, true));
}

TEST(FramePairing, WindowZeroRunsOnEveryFrame) {
  FramePairing p(0);
  EXPECT_TRUE(p.arrived(0, 100 * kMs, 1000 * kMs, true));
  EXPECT_EQ(p.take(), (Fresh{true, false}));
  EXPECT_TRUE(p.arrived(1, 100 * kMs, 1000 * kMs, true));
  EXPECT_EQ(p.take(), (Fresh{false, true}));
}

TEST(FramePairing, FreeRunningCamerasFurtherApartThanTheWindowEachRunAfterAtMostTheWindow) {
  // Unsynchronised cameras 2.5 ms out of phase: no pairs, every frame runs, none waits longer.
  FramePairing p(kWindow);
  int runs = 0;
  std::int64_t now = 0;
  std::int64_t waiting_since = 0;
  for (int f = 0; f < 100; ++f) {
    for (int k = 0; k < 2; ++k) {
      const std::int64_t ts = f * kPeriod + k * (kPeriod / 2);
      const std::int64_t arrival = ts + kMs / 2;
      // hand_node's loop wakes at the deadline when nothing arrives before it.
      if (p.any_waiting() && p.deadline_ns() <= arrival) {
        now = p.deadline_ns();
        ASSERT_TRUE(p.due(now));
        ASSERT_LE(now - waiting_since, kWindow);
        const Fresh fr = p.take();
        runs += fr[0] + fr[1];
      }
      ASSERT_GE(arrival, now);
      now = arrival;
      ASSERT_FALSE(p.waiting(k));
      if (!p.any_waiting()) waiting_since = now;
      if (p.arrived(k, ts, now, true)) {
        const Fresh fr = p.take();
        runs += fr[0] + fr[1];
      } else {
        ASSERT_LE(p.deadline_ns() - now, kWindow);
      }
    }
  }
  if (p.any_waiting()) {
    const Fresh fr = p.take();
    runs += fr[0] + fr[1];
  }
  EXPECT_EQ(runs, 200);
}

}  // namespace
}  // namespace tactile::hand
