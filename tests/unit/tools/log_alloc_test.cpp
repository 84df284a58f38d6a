// tactile_record's per-message path allocates nothing once its buffers have grown (STYLE.md 4).
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "process.hpp"
#include "tactile/recording/log_writer.hpp"

namespace tactile::recording {
namespace {

TEST(LogWriterAlloc, AppendAllocatesNothingInSteadyState) {
  testing::TempDir dir;
  LogWriterOptions o;
  o.frame_bytes = 16 << 10;  // many frames: compression and writing are on the path too
  LogWriter w(dir / "a.tlog", v1::LogHeader{}, o);
  std::string payload(4000, 'x');
  for (std::size_t i = 0; i < payload.size(); i += 3)
    payload[i] = static_cast<char>(i);
  const std::span<const std::uint8_t> p(reinterpret_cast<const std::uint8_t*>(payload.data()),
                                        payload.size());
  for (int i = 0; i < 50; ++i)  // warm up: buffers grow to size
    ASSERT_EQ(w.append(i, "frame/left", "tcp://127.0.0.1:5555", v1::PAYLOAD_KIND_ENVELOPE, p),
              WriteStatus::kOk);
  std::size_t allocations = 0;
  {
    testing::AllocationScope scope;
    for (int i = 0; i < 200; ++i) {
      (void)w.append(i, "frame/left", "tcp://127.0.0.1:5555", v1::PAYLOAD_KIND_ENVELOPE, p);
      (void)w.poll();
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_GT(w.frames(), 10U);
  EXPECT_EQ(w.close(), WriteStatus::kOk);
}

}  // namespace
}  // namespace tactile::recording
