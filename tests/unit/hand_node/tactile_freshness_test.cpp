// TactileFreshness: a fingertip is stale before its first whole frame and once none came for
// stale_after_s of hand_node's running time; a fingertip is waited for when its frames came lately
// here or its last one left sensor_node shortly before its partner's (frames queued while hand_node
// did not run).
#include "tactile_freshness.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace tactile::hand {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kStale = 30 * kMs;

TEST(TactileFreshness, StaleBeforeTheFirstFrameAndOnceNoneCameForStaleAfter) {
  TactileFreshness f(kStale);
  struct Row {
    std::int64_t t_ms;
    bool stale0;
    bool stale1;
  };
  EXPECT_TRUE(f.stale(0, 0));
  f.arrived(0, 100 * kMs, 90 * kMs);
  const Row rows[] = {
      {100, false, true},  // fingertip 1 never sent one
      {130, false, true},  // exactly stale_after_s: still fresh
      {131, true, true},
  };
  for (const Row& r : rows) {
    EXPECT_EQ(f.stale(0, r.t_ms * kMs), r.stale0) << r.t_ms;
    EXPECT_EQ(f.stale(1, r.t_ms * kMs), r.stale1) << r.t_ms;
  }
  f.arrived(0, 140 * kMs, 135 * kMs);
  EXPECT_FALSE(f.stale(0, 140 * kMs));
  EXPECT_TRUE(f.has_frame(0));
  EXPECT_FALSE(f.has_frame(1));
}

TEST(TactileFreshness, TimeHandNodeDidNotRunIsNotCountedTowardsStaleness) {
  // The stop of a CI run: fingertip 0's last frame came at 100 ms, then hand_node was stopped
  // for 60 ms (twice stale_after_s) and woke at 165 ms before ZeroMQ's I/O thread had handed it
  // the frames queued meanwhile.
  TactileFreshness f(kStale);
  f.arrived(0, 100 * kMs, 95 * kMs);
  EXPECT_TRUE(f.stale(0, 165 * kMs)) << "counting the time away";
  f.not_running(60 * kMs);
  EXPECT_FALSE(f.stale(0, 165 * kMs));
  EXPECT_FALSE(f.stale(0, 190 * kMs)) << "30 ms of running time since its last frame";
  EXPECT_TRUE(f.stale(0, 191 * kMs)) << "a sensor that stopped is stale stale_after_s on";
  EXPECT_TRUE(f.live(0, 185 * kMs, 500 * kMs)) << "and worth waiting for until then";
  EXPECT_FALSE(f.live(0, 191 * kMs, 500 * kMs));
  // A fingertip that never sent a frame stays stale.
  EXPECT_TRUE(f.stale(1, 165 * kMs));
  EXPECT_FALSE(f.has_frame(1));
}

TEST(TactileFreshness, AFingertipIsWaitedForWhileItsFramesComeOrWereSentAlongside) {
  struct Row {
    std::int64_t arrived_ms;       // fingertip 1's last whole frame came here
    std::int64_t sent_ms;          // and left sensor_node
    std::int64_t now_ms;           // fingertip 0's frame comes here
    std::int64_t partner_sent_ms;  // and left sensor_node
    bool live;
    const char* why;
  };
  const Row rows[] = {
      {100, 95, 110, 300, true, "came lately here"},
      {100, 95, 130, 300, true, "came exactly stale_after_s ago"},
      {100, 95, 131, 200, false, "nothing for longer, and sent long before: a dead sensor"},
      // hand_node did not run for 200 ms: fingertip 1's last frame came here long ago, but it
      // left sensor_node alongside this one; its next frame is queued behind.
      {100, 295, 500, 300, true, "sent alongside, queued"},
      {100, 270, 500, 300, true, "sent exactly stale_after_s before"},
      {100, 269, 500, 300, false, "sent longer before"},
  };
  for (const Row& r : rows) {
    TactileFreshness f(kStale);
    f.arrived(1, r.arrived_ms * kMs, r.sent_ms * kMs);
    EXPECT_EQ(f.live(1, r.now_ms * kMs, r.partner_sent_ms * kMs), r.live) << r.why;
  }
  TactileFreshness none(kStale);
  EXPECT_FALSE(none.live(1, 0, 0)) << "no frame yet: nothing to wait for";
}

}  // namespace
}  // namespace tactile::hand
