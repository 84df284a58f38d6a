// The pure parts of the camera seam: statuses, frame id unwrapping, reconnect policy, options.
#include "tactile/camera/camera.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "tactile/camera/aravis_camera.hpp"
#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/v1/tactile.pb.h"

namespace tactile::camera {
namespace {

using namespace std::chrono_literals;

TEST(FrameStatus, NumbersAreTheWireNumbers) {
  struct Row {
    FrameStatus status;
    v1::FrameStatus wire;
  };
  const Row rows[] = {
      {FrameStatus::kComplete, v1::FRAME_STATUS_COMPLETE},
      {FrameStatus::kMissingPackets, v1::FRAME_STATUS_MISSING_PACKETS},
      {FrameStatus::kSizeMismatch, v1::FRAME_STATUS_SIZE_MISMATCH},
      {FrameStatus::kTimeout, v1::FRAME_STATUS_TIMEOUT},
      {FrameStatus::kWrongFormat, v1::FRAME_STATUS_WRONG_FORMAT},
      {FrameStatus::kAborted, v1::FRAME_STATUS_ABORTED},
      {FrameStatus::kCameraError, v1::FRAME_STATUS_CAMERA_ERROR},
  };
  for (const auto& row : rows) {
    EXPECT_EQ(static_cast<int>(row.status), static_cast<int>(row.wire)) << to_string(row.status);
    EXPECT_TRUE(v1::FrameStatus_IsValid(static_cast<int>(row.status)));
  }
}

TEST(FrameStatus, Names) {
  EXPECT_EQ(to_string(FrameStatus::kComplete), "complete");
  EXPECT_EQ(to_string(FrameStatus::kMissingPackets), "missing packets");
  EXPECT_EQ(to_string(FrameStatus::kCameraError), "camera error");
}

TEST(PixelFormatText, RoundTripAndRejects) {
  EXPECT_EQ(parse_pixel_format("Mono8"), PixelFormat::kMono8);
  EXPECT_EQ(parse_pixel_format("Mono16"), PixelFormat::kMono16);
  EXPECT_EQ(to_string(PixelFormat::kMono16), "Mono16");
  try {
    parse_pixel_format("RGB8");
    FAIL() << "RGB8 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("RGB8"), std::string::npos) << e.what();
  }
  EXPECT_EQ(to_string(FrameFormat{640, 480, PixelFormat::kMono16}), "640x480 Mono16");
  EXPECT_EQ((FrameFormat{640, 480, PixelFormat::kMono16}.payload_bytes()), 614400U);
}

TEST(FrameSequencer, CountsFromZeroAndMeasuresGaps) {
  FrameSequencer s;
  auto a = s.next(100);
  EXPECT_TRUE(a.first_after_start);
  EXPECT_EQ(a.sequence, 0U);
  auto b = s.next(101);
  EXPECT_FALSE(b.first_after_start);
  EXPECT_EQ(b.sequence, 1U);
  EXPECT_EQ(b.frames_lost, 0U);
  auto c = s.next(105);  // 102, 103, 104 lost: a step of 4 frame periods
  EXPECT_EQ(c.sequence, 5U);
  EXPECT_EQ(c.frames_lost, 3U);
}

TEST(FrameSequencer, SixteenBitIdsWrapToOneSkippingZero) {
  FrameSequencer s;
  s.next(65534);
  EXPECT_EQ(s.next(65535).sequence, 1U);
  const auto wrapped = s.next(1);  // GigE Vision 1.x: 65535 is followed by 1
  EXPECT_EQ(wrapped.sequence, 2U);
  EXPECT_EQ(wrapped.frames_lost, 0U);
  const auto gap = s.next(3);  // 2 lost
  EXPECT_EQ(gap.sequence, 4U);
  EXPECT_EQ(gap.frames_lost, 1U);
  // A gap across the wrap: 65533 -> 2 skips 65534, 65535, 1.
  FrameSequencer t;
  t.next(65533);
  const auto across = t.next(2);
  EXPECT_EQ(across.sequence, 4U);
  EXPECT_EQ(across.frames_lost, 3U);
}

TEST(FrameSequencer, ManyWrapsStayContiguous) {
  FrameSequencer s;
  std::uint64_t id = 65000;
  for (std::uint64_t i = 0; i < 200000; ++i) {
    const auto step = s.next(id);
    ASSERT_EQ(step.sequence, i);
    ASSERT_EQ(step.frames_lost, 0U);
    id = id == 65535 ? 1 : id + 1;
  }
}

TEST(FrameSequencer, SixtyFourBitIdsAreTakenAsTheyAre) {
  FrameSequencer s;
  s.next(65535);
  EXPECT_EQ(s.next(65536).sequence, 1U);  // not a wrap: a 64-bit block id counter
  EXPECT_EQ(s.next(70000).sequence, 70000U - 65535U);
  FrameSequencer z;  // a counter that uses 0 is not GigE Vision 1.x
  z.next(0);
  EXPECT_EQ(z.next(1).sequence, 1U);
}

TEST(FrameSequencer, LateFramesKeepTheirPlaceAndChangeNothing) {
  FrameSequencer s;
  s.next(10);
  s.next(12);
  const auto late = s.next(11);
  EXPECT_TRUE(late.late);
  EXPECT_EQ(late.sequence, 1U);
  EXPECT_EQ(late.frames_lost, 0U);
  const auto repeat = s.next(12);
  EXPECT_TRUE(repeat.late);
  EXPECT_EQ(repeat.sequence, 2U);
  EXPECT_EQ(s.next(13).sequence, 3U);
}

TEST(FrameSequencer, RestartContinuesTheSequence) {
  FrameSequencer s;
  s.next(500);
  s.next(501);
  s.restart();
  const auto first = s.next(1);  // the camera restarted its ids
  EXPECT_TRUE(first.first_after_start);
  EXPECT_EQ(first.sequence, 2U);
  EXPECT_EQ(first.frames_lost, 0U);
  EXPECT_EQ(s.next(2).sequence, 3U);
}

TEST(ReconnectPolicy, WaitsForStalenessThenBacksOffExponentially) {
  ReconnectOptions o;
  o.stale_after = 1s;
  o.initial_backoff = 100ms;
  o.max_backoff = 350ms;
  o.backoff_factor = 2.0;
  const std::int64_t ms = 1000000;
  ReconnectPolicy p(o, 0);
  EXPECT_FALSE(p.reopen_due(999 * ms));
  p.on_frame(500 * ms);
  EXPECT_FALSE(p.reopen_due(1499 * ms));
  EXPECT_TRUE(p.reopen_due(1500 * ms));
  p.on_reopen(false, 1500 * ms);  // next try 100 ms later
  EXPECT_EQ(p.failed_attempts(), 1);
  EXPECT_FALSE(p.reopen_due(1599 * ms));
  EXPECT_TRUE(p.reopen_due(1600 * ms));
  p.on_reopen(false, 1600 * ms);  // then 200 ms
  EXPECT_FALSE(p.reopen_due(1799 * ms));
  EXPECT_TRUE(p.reopen_due(1800 * ms));
  p.on_reopen(false, 1800 * ms);  // then 350 ms (capped from 400)
  EXPECT_FALSE(p.reopen_due(2149 * ms));
  EXPECT_TRUE(p.reopen_due(2150 * ms));
  p.on_reopen(false, 2150 * ms);  // stays at the cap
  EXPECT_EQ(p.current_backoff(), 350ms);
  EXPECT_TRUE(p.reopen_due(2500 * ms));
  p.on_reopen(true, 2500 * ms);  // alive again: stale timer and backoff start over
  EXPECT_EQ(p.failed_attempts(), 0);
  EXPECT_EQ(p.current_backoff(), 100ms);
  EXPECT_FALSE(p.reopen_due(3499 * ms));
  EXPECT_TRUE(p.reopen_due(3500 * ms));
}

TEST(ReconnectPolicy, RejectsBadOptionsByName) {
  auto message = [](ReconnectOptions o) {
    try {
      ReconnectPolicy p(o, 0);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  ReconnectOptions o;
  o.stale_after = 0s;
  EXPECT_NE(message(o).find("stale_after"), std::string::npos);
  o = {};
  o.max_backoff = 1ms;
  EXPECT_NE(message(o).find("max_backoff"), std::string::npos);
  o = {};
  o.backoff_factor = 0.5;
  EXPECT_NE(message(o).find("backoff_factor"), std::string::npos);
}

// Each bad option is named with its value in the message, at construction.
TEST(AravisCameraOptions, RejectsBadValuesByName) {
  struct Row {
    const char* option;
    const char* value;
    void (*spoil)(AravisCameraOptions&);
  };
  const Row rows[] = {
      {"camera", "\"\"", [](AravisCameraOptions& o) { o.camera.clear(); }},
      {"interface_address", "eth0", [](AravisCameraOptions& o) { o.interface_address = "eth0"; }},
      {"width", "0", [](AravisCameraOptions& o) { o.width = 0; }},
      {"height", "-3", [](AravisCameraOptions& o) { o.height = -3; }},
      {"frame_rate_hz", "0", [](AravisCameraOptions& o) { o.frame_rate_hz = 0; }},
      {"packet_size_bytes", "70000", [](AravisCameraOptions& o) { o.packet_size_bytes = 70000; }},
      {"socket_buffer_bytes", "1000", [](AravisCameraOptions& o) { o.socket_buffer_bytes = 1000; }},
      {"packet_delay_ns", "-2", [](AravisCameraOptions& o) { o.packet_delay_ns = -2; }},
      {"packet_delay_ns", "20000000",
       [](AravisCameraOptions& o) { o.packet_delay_ns = 20'000'000; }},
      {"buffer_count", "1", [](AravisCameraOptions& o) { o.buffer_count = 1; }},
      {"packet_timeout_ns", "0", [](AravisCameraOptions& o) { o.packet_timeout = 0ms; }},
      {"frame_retention_ns", "0", [](AravisCameraOptions& o) { o.frame_retention = 0ms; }},
  };
  for (const auto& row : rows) {
    AravisCameraOptions o;
    o.camera = "127.0.0.2";
    row.spoil(o);
    try {
      AravisCamera camera(o);
      ADD_FAILURE() << row.option << " accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(row.option), std::string::npos) << what;
      EXPECT_NE(what.find(row.value), std::string::npos) << what;
    }
  }
  AravisCameraOptions good;
  good.camera = "127.0.0.2";
  EXPECT_NO_THROW(good.validate());
}

TEST(FakeGvCameraOptions, RejectsBadValuesByName) {
  struct Row {
    const char* option;
    void (*spoil)(FakeGvCameraOptions&);
  };
  const Row rows[] = {
      {"address", [](FakeGvCameraOptions& o) { o.address = "lo"; }},
      {"serial", [](FakeGvCameraOptions& o) { o.serial = "a-serial-far-too-long"; }},
      {"width", [](FakeGvCameraOptions& o) { o.width = 4096; }},
      {"height", [](FakeGvCameraOptions& o) { o.height = 0; }},
      {"frame_rate_hz", [](FakeGvCameraOptions& o) { o.frame_rate_hz = 2000; }},
      {"gvsp_lost_ratio", [](FakeGvCameraOptions& o) { o.gvsp_lost_ratio = 1.5; }},
  };
  for (const auto& row : rows) {
    FakeGvCameraOptions o;
    row.spoil(o);
    try {
      o.validate();
      ADD_FAILURE() << row.option << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(row.option), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace tactile::camera
