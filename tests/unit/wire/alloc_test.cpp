// The per-frame wire paths allocate nothing once warm: sensor_node's fill + encode, hand_node's
// decode + read (docs/architecture.md, rule 4). ZeroMQ's own message buffers are outside our code.
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "synthetic.hpp"
#include "tactile/wire/arm.hpp"
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

  // The viewers' read, without a calibration, of the same frames.
  std::vector<ElementReading> viewed;
  ASSERT_EQ(read_elements(decoder.envelope().tactile_frame(), viewed), DecodeStatus::kOk);
  {
    tactile::testing::AllocationScope scope;
    for (int k = 0; k < 100; ++k)
      ASSERT_EQ(read_elements(decoder.envelope().tactile_frame(), viewed), DecodeStatus::kOk);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_DOUBLE_EQ(viewed[4].G, 1004.0);
}

// hand_node's Decision of each step, with the slipping elements' ids and the detector's name,
// filled and encoded into reused storage: once it held the most ids, nothing is allocated.
TEST(WireAllocation, DecisionFillAndEncodeAllocateNothingOnceWarm) {
  control::ControllerOutput output;
  output.slip_detector = control::SlipDetectorKind::kLearned;
  const FingertipIds ids{"left", "right"};
  const std::array<std::int64_t, control::kFingertips> received{1, 2};
  v1::Envelope env;
  std::string bytes;
  const auto cycle = [&](std::uint32_t slipping) {
    for (auto& f : output.flags.fingertip) {
      f.slip = slipping > 0;
      f.slipping_elements = slipping;
      for (std::uint32_t k = 0; k < slipping; ++k)
        f.slipping_ids[k] = 3 * k;
    }
    Answers on;
    on.add({0, slipping, 7});
    fill_decision(output, 9, on, received, 0, ids, *env.mutable_decision());
    encode(env, bytes);
  };
  cycle(41);  // warm: the most ids a fingertip of 41 elements names
  std::size_t allocations = 0;
  {
    tactile::testing::AllocationScope scope;
    for (std::uint32_t s = 0; s < 200; ++s)
      cycle(s % 42);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(env.decision().fingertips(1).slipping_element_ids_size(), 199 % 42);
  EXPECT_EQ(env.decision().slip_detector(), "learned");
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
