// The per-frame wire paths allocate nothing once warm: sensor_node's fill + encode, hand_node's
// decode + read (docs/architecture.md, rule 4). ZeroMQ's own message buffers are outside our code.
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "synthetic.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::wire {
namespace {

TEST(WireAllocation, FillEncodeDecodeReadAllocateNothingOnceWarm) {
  testing::SceneOptions o;
  Calibration cal = testing::grid_calibration(o, 8, 5, 60, 14);
  std::vector<ElementReading> readings(cal.elements.size());
  for (std::size_t i = 0; i < readings.size(); ++i) {
    readings[i].id = cal.elements[i].id;
    readings[i].contact = i % 2 == 0;
    readings[i].G = 1000.0 + static_cast<double>(i);
    readings[i].fz = 0.1 * static_cast<double>(i);
  }
  const std::string id = "left";
  v1::Envelope out;
  std::string bytes;
  EnvelopeDecoder decoder;
  ReceivedFrame received;
  received.elements.resize(cal.elements.size());
  FrameHeader h;
  h.status = v1::FRAME_STATUS_COMPLETE;
  const auto cycle = [&](std::uint64_t seq) {
    h.sequence = seq;
    fill_tactile_frame(id, h, readings, cal.mm_per_px, *out.mutable_tactile_frame());
    encode(out, bytes);
    ASSERT_EQ(decoder.decode(bytes_of(bytes)), DecodeStatus::kOk);
    ASSERT_EQ(read_tactile_frame(decoder.envelope().tactile_frame(), cal, received),
              DecodeStatus::kOk);
  };
  for (std::uint64_t s = 0; s < 3; ++s)
    cycle(s);  // warm: buffers grow to size
  std::size_t allocations = 0;
  {
    tactile::testing::AllocationScope scope;
    for (std::uint64_t s = 3; s < 103; ++s)
      cycle(s);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(received.header.sequence, 102U);
  EXPECT_DOUBLE_EQ(received.elements[4].G, 1004.0);
}

TEST(WireAllocation, PlainDecodeDoesAllocateWhichIsWhyTheDecoderExists) {
  // The counter sees what the decoder avoids: a plain decode into a reused Envelope frees and
  // rebuilds the body on every message.
  testing::SceneOptions o;
  Calibration cal = testing::grid_calibration(o, 8, 5, 60, 14);
  std::vector<ElementReading> readings(cal.elements.size());
  for (std::size_t i = 0; i < readings.size(); ++i)
    readings[i].id = cal.elements[i].id;
  v1::Envelope out;
  std::string bytes;
  FrameHeader h;
  h.status = v1::FRAME_STATUS_COMPLETE;
  fill_tactile_frame("left", h, readings, cal.mm_per_px, *out.mutable_tactile_frame());
  encode(out, bytes);
  const auto span = bytes_of(bytes);
  v1::Envelope in;
  decode(span, in);
  tactile::testing::AllocationScope scope;
  decode(span, in);
  EXPECT_GT(scope.count(), 0U);
}

}  // namespace
}  // namespace tactile::wire
