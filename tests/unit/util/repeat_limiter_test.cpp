// util::RepeatLimiter on driven time, and util::log_line through it: a message repeats at most
// once a second, the copies in between counted and said with its next writing.
#include "tactile/util/repeat_limiter.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "process.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"

namespace {

using tactile::util::RepeatLimiter;
constexpr std::int64_t kMs = 1'000'000;

TEST(RepeatLimiter, AMessageFiftyTimesASecondIsWrittenOnceASecondWithItsCount) {
  RepeatLimiter limiter;
  int written = 0;
  std::uint64_t last_count = 0;
  for (int k = 0; k < 150; ++k) {  // 3 s at 50 a second
    const auto d = limiter.offer("left: reference refused: frame size differs", k * 20 * kMs);
    if (d.write) {
      ++written;
      last_count = d.held_back;
    }
  }
  EXPECT_EQ(written, 3);      // at 0 s, 1 s and 2 s
  EXPECT_EQ(last_count, 49);  // the 49 copies between 1 s and 2 s
}

TEST(RepeatLimiter, DifferentMessagesDoNotHoldEachOtherBack) {
  RepeatLimiter limiter;
  EXPECT_TRUE(limiter.offer("a", 0).write);
  EXPECT_TRUE(limiter.offer("b", 1).write);
  EXPECT_FALSE(limiter.offer("a", 2).write);
  const auto d = limiter.offer("a", 1000 * kMs);
  EXPECT_TRUE(d.write);
  EXPECT_EQ(d.held_back, 1U);
  EXPECT_EQ(tactile::util::repeated_suffix(d.held_back), " (repeated 1 times)");
  EXPECT_EQ(tactile::util::repeated_suffix(0), "");
}

TEST(RepeatLimiter, ForgetsTheMessageOfferedLongestAgoWhenFull) {
  RepeatLimiter limiter;
  // Seventeen messages that differ in their words (figures alone would make them one).
  auto message = [](std::size_t k) { return "m" + std::string(k + 1, 'x'); };
  for (std::size_t k = 0; k <= RepeatLimiter::kSlots; ++k)
    EXPECT_TRUE(limiter.offer(message(k), static_cast<std::int64_t>(k)).write);
  EXPECT_TRUE(limiter.offer(message(0), 100).write) << "pushed out, new again";
  EXPECT_FALSE(limiter.offer(message(2), 101).write) << "still remembered";
}

// sensor_node's refusals while a reference is captured from a moving image carry the element and
// its excess G: before, each figure made a new message, and it was written 5 to 50 times a second.
TEST(RepeatLimiter, MessagesThatDifferOnlyInTheirFiguresAreOneMessage) {
  struct Case {
    const char* first;
    const char* then;
    bool same;
  };
  const Case cases[] = {
      {"left: reference refused (element 11, excess G 2000)",
       "left: reference refused (element 0, excess G 1235)", true},
      {"latency 12.5 ms", "latency 3 ms", true},
      {"latency 12.5 ms", "latency -3 ms", false},  // a sign is text
      {"element 7 of 41", "element 7", false},
      {"left: refused", "right: refused", false},
      {"sent 10.", "sent 11.", true},  // a dot after a figure ends the sentence, not the figure
      {"a 1b", "a 1", false},
      {"x", "x1", false},
  };
  for (const Case& c : cases) {
    RepeatLimiter limiter;
    ASSERT_TRUE(limiter.offer(c.first, 0).write);
    EXPECT_EQ(limiter.offer(c.then, kMs).write, !c.same) << c.first << " / " << c.then;
  }
  // What is written after the period is the latest copy, with the count of those held back.
  RepeatLimiter limiter;
  for (int k = 0; k < 50; ++k)
    limiter.offer("element " + std::to_string(k % 41) + " refused", k * 20 * kMs);
  const auto d = limiter.offer("element 3 refused", 1000 * kMs);
  EXPECT_TRUE(d.write);
  EXPECT_EQ(d.held_back, 49U);
}

// log_warn on standard error (redirected to a file): 100 identical warnings in a moment are one
// line; an info line is never held back.
TEST(RepeatLimiter, LogLineWritesARepeatedWarningOnce) {
  tactile::testing::TempDir dir;
  const std::string path = (dir / "err").string();
  std::fflush(stderr);
  const int saved = dup(STDERR_FILENO);
  ASSERT_NE(std::freopen(path.c_str(), "w", stderr), nullptr);
  for (int k = 0; k < 100; ++k)
    tactile::util::log_warn("camera {}: the same fault", "left");
  tactile::util::log_info("an info line");
  tactile::util::log_info("an info line");
  std::fflush(stderr);
  dup2(saved, STDERR_FILENO);
  close(saved);
  const std::string err = tactile::util::read_file(path);
  std::size_t warnings = 0;
  for (std::size_t at = 0; (at = err.find("the same fault", at)) != std::string::npos; ++at)
    ++warnings;
  EXPECT_EQ(warnings, 1U) << err;
  std::size_t infos = 0;
  for (std::size_t at = 0; (at = err.find("an info line", at)) != std::string::npos; ++at)
    ++infos;
  EXPECT_EQ(infos, 2U) << err;
}

}  // namespace
