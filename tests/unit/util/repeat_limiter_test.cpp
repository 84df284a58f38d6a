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
  for (std::size_t k = 0; k <= RepeatLimiter::kSlots; ++k)
    EXPECT_TRUE(limiter.offer("m" + std::to_string(k), static_cast<std::int64_t>(k)).write);
  EXPECT_TRUE(limiter.offer("m0", 100).write) << "pushed out, new again";
  EXPECT_FALSE(limiter.offer("m2", 101).write) << "still remembered";
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
