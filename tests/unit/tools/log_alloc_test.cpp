// The per-message paths of tactile_record and tactile_live allocate nothing once their buffers
// have grown (docs/architecture.md, rule 4).
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "dashboard.hpp"
#include "process.hpp"
#include "tactile/recording/log_writer.hpp"
#include "tactile/wire/envelope.hpp"

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
  const std::span<const std::uint8_t> p = wire::bytes_of(payload);
  const std::string topic = wire::frame_topic("left");
  for (int i = 0; i < 50; ++i)  // warm up: buffers grow to size
    ASSERT_EQ(w.append(i, topic, "tcp://127.0.0.1:5555", v1::PAYLOAD_KIND_ENVELOPE, p),
              WriteStatus::kOk);
  std::size_t allocations = 0;
  {
    testing::AllocationScope scope;
    for (int i = 0; i < 200; ++i) {
      (void)w.append(i, topic, "tcp://127.0.0.1:5555", v1::PAYLOAD_KIND_ENVELOPE, p);
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

namespace tactile::live {
namespace {

// tactile_live takes each frame without allocating once it has seen the fingertip.
TEST(LiveModelAlloc, FramesAllocateNothingInSteadyState) {
  LiveModel m({});
  v1::Envelope env;
  auto* f = env.mutable_tactile_frame();
  f->set_sensor_id("left");
  f->set_status(v1::FRAME_STATUS_COMPLETE);
  for (std::uint32_t e = 0; e < 41; ++e) {
    auto* r = f->add_elements();
    r->set_id(e);
    r->set_contact(e % 3 == 0);
    r->set_fz_n(0.1 * e);
    r->set_has_displacement(true);
    r->set_dy_mm(0.001 * e);
  }
  std::vector<std::string> frames;
  for (std::uint64_t k = 0; k < 60; ++k) {
    f->set_sequence(k);
    std::string buf;
    wire::encode(env, buf);
    frames.push_back(std::move(buf));
  }
  const std::string topic = wire::frame_topic("left");
  auto add = [&](std::size_t k) {
    m.add(topic, wire::bytes_of(frames[k]), static_cast<std::int64_t>(k) * 10'000'000);
  };
  for (std::size_t k = 0; k < 10; ++k)
    add(k);
  std::size_t allocations = 0;
  {
    testing::AllocationScope scope;
    for (std::size_t k = 10; k < 60; ++k)
      add(k);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(m.state().fingertips.at(0).sequence, 59U);
}

}  // namespace
}  // namespace tactile::live
