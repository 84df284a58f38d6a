// The per-message paths of tactile_record, tactile_live and tactile_web allocate nothing once
// their buffers have grown (docs/architecture.md, rule 4).
#include <gtest/gtest.h>

#include <optional>

#include "alloc_counter.hpp"
#include "dashboard.hpp"
#include "process.hpp"
#include "server.hpp"
#include "snapshot.hpp"
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

// tactile_live takes each frame, and each of hand_node's decisions, without allocating once it
// has seen the fingertip: showing hand_node's decisions, and recomputing with each detector.
TEST(LiveModelAlloc, FramesAndDecisionsAllocateNothingInSteadyState) {
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
  std::vector<std::string> decisions;
  for (std::uint64_t k = 0; k < 60; ++k) {
    f->set_sequence(k);
    std::string buf;
    wire::encode(env, buf);
    frames.push_back(std::move(buf));
  }
  v1::Envelope dec;
  dec.mutable_decision()->set_slip_detector("learned");
  auto* tip = dec.mutable_decision()->add_fingertips();
  tip->set_sensor_id("left");
  for (std::uint64_t k = 0; k < 60; ++k) {
    tip->set_slip(k % 2 == 0);
    tip->clear_slipping_element_ids();
    for (std::uint32_t e = 0; e < k % 5; ++e)
      tip->add_slipping_element_ids(3 * e);
    std::string buf;
    wire::encode(dec, buf);
    decisions.push_back(std::move(buf));
  }
  const std::string topic = wire::frame_topic("left");
  for (const std::optional<control::SlipDetectorKind> recompute :
       {std::optional<control::SlipDetectorKind>{},
        std::optional{control::SlipDetectorKind::kPaper},
        std::optional{control::SlipDetectorKind::kField},
        std::optional{control::SlipDetectorKind::kLearned}}) {
    SCOPED_TRACE(recompute ? control::to_string(*recompute) : "hand_node's decisions");
    LiveModel m({control::Config{}, 8, recompute});
    auto add = [&](std::size_t k) {
      m.add(topic, wire::bytes_of(frames[k]), static_cast<std::int64_t>(k) * 10'000'000);
      m.add(wire::kDecisionTopic, wire::bytes_of(decisions[k]),
            static_cast<std::int64_t>(k) * 10'000'000 + 1);
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
    // The last decision (59 % 5 = 4 elements: 0, 3, 6, 9) is shown unless recomputing.
    EXPECT_EQ(m.state().flags_from, recompute ? FlagSource::kRecomputed : FlagSource::kHandNode);
    if (!recompute) {
      EXPECT_TRUE(m.state().fingertips.at(0).elements.at(9).slip);
    }
  }
}

// tactile_web: each frame into the model, the update written and handed to the slot, and a
// viewer's connection taking it, once the buffers have their room.
TEST(WebUpdateAlloc, FramesUpdatesAndAViewerAllocateNothingInSteadyState) {
  LiveModel m({});
  web::SnapshotWriter writer({}, control::Config{});
  web::UpdateSlot slot;
  v1::Envelope env;
  std::vector<std::string> frames;
  for (std::uint64_t k = 0; k < 200; ++k) {
    for (const char* id : {"left", "right"}) {
      auto* f = env.mutable_tactile_frame();
      f->Clear();
      f->set_sensor_id(id);
      f->set_status(v1::FRAME_STATUS_COMPLETE);
      f->set_sequence(k);
      for (std::uint32_t e = 0; e < 41; ++e) {
        auto* r = f->add_elements();
        r->set_id(e);
        r->set_contact((e + k) % 3 == 0);
        r->set_fz_n(0.1 * e + 0.001 * static_cast<double>(k));
        r->set_fx_n(-0.01 * e);
        r->set_fy_n(0.003 * static_cast<double>(k));
        r->set_has_displacement(true);
        r->set_dy_mm(0.001 * e);
      }
      std::string buf;
      wire::encode(env, buf);
      frames.push_back(std::move(buf));
    }
  }
  std::string update;
  std::string point;
  std::string viewer;
  std::uint64_t seen = 0;
  web::UpdateCounters counters;
  auto step = [&](std::size_t k) {
    for (std::size_t side = 0; side < 2; ++side) {
      m.add(wire::frame_topic(side == 0 ? "left" : "right"), wire::bytes_of(frames[2 * k + side]),
            static_cast<std::int64_t>(k) * 10'000'000);
    }
    m.tick(static_cast<std::int64_t>(k) * 10'000'000, 1'763'700'000'000'000'000);
    ++counters.update;
    writer.write(m.state(), counters, update);
    writer.write_point(m.state(), point);
    slot.publish(update, point);
    (void)slot.wait_newer(seen, viewer, std::chrono::milliseconds(0));
  };
  for (std::size_t k = 0; k < 20; ++k)
    step(k);
  std::size_t allocations = 0;
  {
    testing::AllocationScope scope;
    for (std::size_t k = 20; k < 200; ++k)
      step(k);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_NE(viewer.find(R"("id":"right","sequence":199,)"), std::string::npos) << viewer;
}

}  // namespace
}  // namespace tactile::live
