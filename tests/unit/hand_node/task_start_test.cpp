// TaskStart: the task starts once the arm controller answered and each fingertip sent enough
// whole frames; until then what it waits for is said at once and again every report period.
#include "task_start.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

namespace tactile::hand {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kReport = 5000 * kMs;

struct Row {
  std::int64_t t_ms;
  bool arm_heard;
  std::array<std::uint64_t, 2> frames;
  bool start;
  bool report_waiting;
};

void run(std::initializer_list<Row> rows) {
  TaskStart s(20, kReport);
  std::size_t i = 0;
  for (const Row& r : rows) {
    SCOPED_TRACE(testing::Message() << "row " << i++ << " at " << r.t_ms << " ms");
    const TaskStart::Check c = s.check(r.t_ms * kMs, r.arm_heard, r.frames);
    EXPECT_EQ(c.start, r.start);
    EXPECT_EQ(c.report_waiting, r.report_waiting);
  }
}

TEST(TaskStart, WithoutAnArmControllerTheWaitIsSaidAgainEveryPeriod) {
  run({
      {100, false, {0, 0}, false, true},  // at once
      {105, false, {1, 1}, false, false},
      {5099, false, {30, 30}, false, false},
      {5100, false, {40, 40}, false, true},  // a period later
      {10'099, false, {50, 50}, false, false},
      {10'100, false, {60, 60}, false, true},
      {60'000, false, {70, 70}, false, true},  // a long gap: once, and the period counts from it
      {64'999, false, {70, 70}, false, false},
  });
}

TEST(TaskStart, StartsOnceTheArmAnsweredAndBothFingertipsSentEnough) {
  run({
      {0, true, {0, 0}, false, true},
      {10, true, {20, 19}, false, false},  // one fingertip short
      {20, false, {25, 25}, false, false},
      {30, true, {20, 20}, true, false},
      {40, true, {20, 20}, false, false},     // once
      {10'000, false, {0, 0}, false, false},  // nothing more to say
  });
}

TEST(TaskStart, ItsTimeZeroIsTheStart) {
  TaskStart s(1, kReport);
  EXPECT_FALSE(s.started());
  s.check(3 * kMs, true, {0, 1});
  EXPECT_FALSE(s.started());
  EXPECT_TRUE(s.check(7 * kMs, true, {1, 1}).start);
  EXPECT_TRUE(s.started());
  EXPECT_EQ(s.start_ns(), 7 * kMs);
}

}  // namespace
}  // namespace tactile::hand
