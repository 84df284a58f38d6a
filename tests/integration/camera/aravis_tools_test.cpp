// Our camera code against Aravis's own programs, over real GVCP and GVSP: AravisCamera
// receives from arv-fake-gv-camera-0.8 (a separate process), and arv-tool-0.8 and
// arv-camera-test-0.8 talk to our FakeGvCamera. Each run is in a private network namespace
// with 127.0.0.2 and 127.0.0.3 on lo; child processes live in it and are killed with the test.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/child_process.hpp"
#include "support/test_images.hpp"
#include "tactile/camera/aravis_camera.hpp"
#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/util/clock.hpp"

namespace tactile::camera {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::run_program;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Waits for a GigE Vision device to answer on `address`, or fails with the child's output.
void wait_for_camera(const std::string& address, ChildProcess& child) {
  const std::int64_t deadline = util::monotonic_ns() + 10'000'000'000LL;
  while (!gvcp_device_answers(address, 300ms)) {
    ASSERT_TRUE(child.running()) << "the camera process ended: " << child.output();
    ASSERT_LT(util::monotonic_ns(), deadline)
        << "no GVCP answer from " << address << " within 10 s: " << child.output();
  }
}

// The fake camera's own image: a diagonal ramp, (x + y + frame id) mod 255 in Mono8 and
// 256 * (x + y + frame id) mod 65535 in Mono16, at the default gain and exposure.
std::uint32_t aravis_ramp(PixelFormat format, int x, int y, std::uint64_t frame_id) {
  const auto sum = static_cast<std::uint64_t>(x) + static_cast<std::uint64_t>(y) + frame_id;
  return format == PixelFormat::kMono8 ? static_cast<std::uint32_t>(sum % 255)
                                       : static_cast<std::uint32_t>((256 * sum) % 65535);
}

class AravisFakeProcess : public ::testing::TestWithParam<PixelFormat> {};

TEST_P(AravisFakeProcess, AravisCameraReceivesWholeFramesOfTheRightSize) {
  const PixelFormat format = GetParam();
  ChildProcess fake({"arv-fake-gv-camera-0.8", "-i", "127.0.0.2", "-s", "PROC1"});
  wait_for_camera("127.0.0.2", fake);

  {
    // Released before the camera process goes: a controller that outlives its camera spends
    // Aravis's control timeouts (seconds) saying goodbye.
    AravisCameraOptions o;
    o.camera = "127.0.0.2";
    o.width = 640;
    o.height = 480;
    o.pixel_format = format;
    o.frame_rate_hz = 50.0;
    AravisCamera camera(o);
    camera.start();
    int complete = 0;
    std::uint64_t previous_sequence = 0;
    for (int i = 0; i < 25; ++i) {
      const Frame f = camera.wait_frame(2s);
      ASSERT_TRUE(f.received) << "no frame within 2 s; process output: " << fake.output();
      if (i > 0) {
        EXPECT_EQ(f.sequence, previous_sequence + 1);
      }
      previous_sequence = f.sequence;
      if (f.status != FrameStatus::kComplete) {
        EXPECT_EQ(i, 0) << "only the first frame may come before the socket buffer is set";
        continue;
      }
      ++complete;
      ASSERT_EQ(f.image.width, 640);
      ASSERT_EQ(f.image.height, 480);
      ASSERT_EQ(f.image.format, format);
      ASSERT_EQ(f.image.stride_bytes, 640 * bytes_per_pixel(format));
      for (int y = 0; y < 480; y += 7) {
        for (int x = 0; x < 640; x += 5) {
          ASSERT_EQ(f.image.at(x, y), aravis_ramp(format, x, y, f.camera_frame_id))
              << "pixel (" << x << ", " << y << ") of frame " << f.camera_frame_id;
        }
      }
    }
    EXPECT_GE(complete, 24);
    EXPECT_EQ(camera.counters().incomplete, static_cast<std::uint64_t>(25 - complete));
    if (complete == 25) {
      EXPECT_EQ(camera.counters().missing_packets, 0U);
    }
    camera.stop();
  }
  const int status = fake.stop();
  EXPECT_TRUE(status == 0 || status == 128 + 15) << "exit status " << status;
  EXPECT_FALSE(fake.running());
}

// Aravis's own fake camera (another implementation of GenICam's OffsetX/OffsetY/Width/Height)
// takes the region AravisCamera asks for and sends frames of that size.
TEST(AravisFakeProcessRegion, TakesTheRegionOfInterestAndSendsFramesOfItsSize) {
  ChildProcess fake({"arv-fake-gv-camera-0.8", "-i", "127.0.0.2", "-s", "PROC2"});
  wait_for_camera("127.0.0.2", fake);
  {
    AravisCameraOptions o;
    o.camera = "127.0.0.2";
    o.width = 640;
    o.height = 480;
    o.region = {101, 87, 333, 219};
    o.frame_rate_hz = 50.0;
    AravisCamera camera(o);
    camera.start();
    EXPECT_EQ(camera.format(), (FrameFormat{333, 219, PixelFormat::kMono8}));
    int complete = 0;
    for (int i = 0; i < 10; ++i) {
      const Frame f = camera.wait_frame(2s);
      ASSERT_TRUE(f.received) << "no frame within 2 s; process output: " << fake.output();
      if (f.status != FrameStatus::kComplete) continue;
      ++complete;
      ASSERT_EQ(f.image.width, 333);
      ASSERT_EQ(f.image.height, 219);
      EXPECT_EQ(f.image.origin_x, 101);
      EXPECT_EQ(f.image.origin_y, 87);
      // Its ramp is drawn in the frame's own coordinates.
      for (int y = 0; y < 219; y += 7) {
        for (int x = 0; x < 333; x += 5) {
          ASSERT_EQ(f.image.at(x, y), aravis_ramp(PixelFormat::kMono8, x, y, f.camera_frame_id))
              << "pixel (" << x << ", " << y << ") of frame " << f.camera_frame_id;
        }
      }
    }
    EXPECT_GE(complete, 9);
    camera.stop();
  }
  const int status = fake.stop();
  EXPECT_TRUE(status == 0 || status == 128 + 15) << "exit status " << status;
}

INSTANTIATE_TEST_SUITE_P(Mono8AndMono16, AravisFakeProcess,
                         ::testing::Values(PixelFormat::kMono8, PixelFormat::kMono16),
                         [](const auto& p) { return std::string(to_string(p.param)); });

FakeGvCameraOptions rig_camera(const std::string& address, const std::string& serial) {
  FakeGvCameraOptions o;
  o.address = address;
  o.serial = serial;
  o.width = 640;
  o.height = 480;
  o.pixel_format = PixelFormat::kMono16;
  o.frame_rate_hz = 50.0;
  return o;
}

TEST(ArvTool, ListsBothOfOurFakeCameras) {
  FakeGvCamera left(rig_camera("127.0.0.2", "RIG-L"));
  FakeGvCamera right(rig_camera("127.0.0.3", "RIG-R"));
  const auto listed = run_program({"arv-tool-0.8"}, 15s);
  ASSERT_FALSE(listed.timed_out) << listed.output;
  EXPECT_EQ(listed.status, 0) << listed.output;
  EXPECT_TRUE(contains(listed.output, "Aravis-Fake-RIG-L (127.0.0.2)")) << listed.output;
  EXPECT_TRUE(contains(listed.output, "Aravis-Fake-RIG-R (127.0.0.3)")) << listed.output;
}

TEST(ArvTool, ReadsAndWritesFeaturesOfOurFakeCamera) {
  FakeGvCamera camera(rig_camera("127.0.0.3", "RIG-R"));
  const auto read =
      run_program({"arv-tool-0.8", "-a", "127.0.0.3", "control", "DeviceID", "DeviceVendorName",
                   "Width", "Height", "PixelFormat", "AcquisitionFrameRate"},
                  15s);
  ASSERT_FALSE(read.timed_out) << read.output;
  EXPECT_EQ(read.status, 0) << read.output;
  EXPECT_TRUE(contains(read.output, "DeviceID = RIG-R")) << read.output;
  EXPECT_TRUE(contains(read.output, "DeviceVendorName = Aravis")) << read.output;
  EXPECT_TRUE(contains(read.output, "Width = 640")) << read.output;
  EXPECT_TRUE(contains(read.output, "Height = 480")) << read.output;
  EXPECT_TRUE(contains(read.output, "PixelFormat = Mono16")) << read.output;
  EXPECT_TRUE(contains(read.output, "AcquisitionFrameRate = 50")) << read.output;

  const auto write = run_program({"arv-tool-0.8", "-a", "127.0.0.3", "control", "Width=320"}, 15s);
  EXPECT_EQ(write.status, 0) << write.output;
  const auto again = run_program({"arv-tool-0.8", "-a", "127.0.0.3", "control", "Width"}, 15s);
  EXPECT_TRUE(contains(again.output, "Width = 320")) << again.output;
}

TEST(ArvCameraTest, AravisOwnReceiverStreamsFromOurFakeCamera) {
  FakeGvCamera camera(rig_camera("127.0.0.2", "RIG-L"));
  Image image(640, 480, PixelFormat::kMono16);
  testing::render_pattern(image, 0, 1);
  ASSERT_TRUE(camera.publish(image.view(), 0, 1000));
  // Socket buffer sized to the payload (-a) and 8 KiB packets (-i): with its defaults the
  // tool loses most frames here, as the notes say of the default socket buffer.
  const auto run = run_program({"arv-camera-test-0.8", "-n", "Aravis-Fake-RIG-L", "-f", "50",
                                "--no-packet-socket", "-r", "-a", "-i", "8192", "--duration=2"},
                               20s);
  ASSERT_FALSE(run.timed_out) << run.output;
  EXPECT_EQ(run.status, 0) << run.output;
  EXPECT_TRUE(contains(run.output, "payload                = 614400 bytes")) << run.output;
  const std::string key = "n_completed_buffers    = ";
  const auto at = run.output.find(key);
  ASSERT_NE(at, std::string::npos) << run.output;
  EXPECT_GT(std::stoul(run.output.substr(at + key.size())), 10U) << run.output;
  EXPECT_GT(camera.frames_sent(), 20U) << run.output;
  EXPECT_TRUE(camera.last_sent().format_matched);
  EXPECT_EQ(camera.last_sent().timestamp_ns, 1000);
}

}  // namespace
}  // namespace tactile::camera
