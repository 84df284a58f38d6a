// ReplayCamera: files served in order, with their statuses, timestamps, pace and counters.
#include "tactile/camera/replay_camera.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "support/test_images.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/pgm.hpp"

namespace tactile::camera {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

class ReplayCameraTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "tactile_replay_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, int width, int height, PixelFormat format,
                 std::uint64_t k) {
    Image image(width, height, format);
    testing::render_pattern(image, k, 7);
    const fs::path path = dir_ / name;
    util::write_pgm(path, image.view());
    return path;
  }

  fs::path dir_;
};

TEST_F(ReplayCameraTest, ServesFilesInOrderWithTheirPixels) {
  ReplayCameraOptions o;
  for (std::uint64_t k = 0; k < 4; ++k) {
    o.files.push_back(write("f" + std::to_string(k) + ".pgm", 32, 24, PixelFormat::kMono16, k));
  }
  o.paced = false;
  o.frame_rate_hz = 50.0;
  o.start_timestamp_ns = 1000;
  ReplayCamera camera(o);
  camera.start();
  EXPECT_EQ(camera.format(), (FrameFormat{32, 24, PixelFormat::kMono16}));
  EXPECT_EQ(camera.nominal_period(), 20ms);
  for (std::uint64_t k = 0; k < 4; ++k) {
    const Frame f = camera.wait_frame(0ns);
    ASSERT_TRUE(f.received);
    EXPECT_EQ(f.status, FrameStatus::kComplete);
    EXPECT_EQ(testing::compare_to_pattern(f.image, k, 7), "");
    EXPECT_EQ(f.camera_frame_id, k + 1);
    EXPECT_EQ(f.sequence, k);
    EXPECT_EQ(f.first_after_start, k == 0);
    EXPECT_EQ(f.camera_timestamp_ns, 1000 + static_cast<std::int64_t>(k) * 20000000);
    EXPECT_GT(f.receive_timestamp_ns, 0);
  }
  EXPECT_TRUE(camera.finished());
  const Frame end = camera.wait_frame(1s);
  EXPECT_FALSE(end.received);
  const CameraCounters c = camera.counters();
  EXPECT_EQ(c.frames, 4U);
  EXPECT_EQ(c.completed, 4U);
  EXPECT_EQ(c.incomplete, 0U);
}

TEST_F(ReplayCameraTest, WrongSizeAndWrongDepthFilesAreReported) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 32, 24, PixelFormat::kMono8, 0),
             write("b.pgm", 31, 24, PixelFormat::kMono8, 1),   // wrong width
             write("c.pgm", 32, 24, PixelFormat::kMono16, 2),  // wrong depth
             write("d.pgm", 32, 24, PixelFormat::kMono8, 3)};
  o.paced = false;
  ReplayCamera camera(o);
  camera.start();
  const FrameStatus expected[] = {FrameStatus::kComplete, FrameStatus::kWrongFormat,
                                  FrameStatus::kWrongFormat, FrameStatus::kComplete};
  for (std::uint64_t k = 0; k < 4; ++k) {
    const Frame f = camera.wait_frame(0ns);
    ASSERT_TRUE(f.received);
    EXPECT_EQ(f.status, expected[k]) << "file " << k << ": " << to_string(f.status);
    EXPECT_EQ(f.sequence, k);
    if (f.status == FrameStatus::kComplete) {
      EXPECT_EQ(testing::compare_to_pattern(f.image, k, 7), "");
    } else {
      EXPECT_EQ(f.image.data, nullptr);
    }
  }
  EXPECT_EQ(camera.counters().incomplete, 2U);
  EXPECT_EQ(camera.counters().completed, 2U);
}

TEST_F(ReplayCameraTest, ExpectedFormatIsEnforcedFromTheFirstFile) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 32, 24, PixelFormat::kMono8, 0)};
  o.paced = false;
  o.expected_format = FrameFormat{64, 48, PixelFormat::kMono8};
  ReplayCamera camera(o);
  camera.start();
  EXPECT_EQ(camera.wait_frame(0ns).status, FrameStatus::kWrongFormat);
}

TEST_F(ReplayCameraTest, LoopsAndKeepsCounting) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 8, 8, PixelFormat::kMono8, 0),
             write("b.pgm", 8, 8, PixelFormat::kMono8, 1)};
  o.paced = false;
  o.loop = true;
  ReplayCamera camera(o);
  camera.start();
  for (std::uint64_t n = 0; n < 7; ++n) {
    const Frame f = camera.wait_frame(0ns);
    ASSERT_EQ(f.status, FrameStatus::kComplete);
    EXPECT_EQ(testing::compare_to_pattern(f.image, n % 2, 7), "");
    EXPECT_EQ(f.sequence, n);
  }
  EXPECT_FALSE(camera.finished());
}

TEST_F(ReplayCameraTest, OnDemandReadingReportsAFileThatVanished) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 8, 8, PixelFormat::kMono8, 0),
             write("b.pgm", 8, 8, PixelFormat::kMono8, 1),
             write("c.pgm", 8, 8, PixelFormat::kMono8, 2)};
  o.paced = false;
  o.preload = false;
  ReplayCamera camera(o);
  camera.start();
  fs::remove(o.files[1]);
  EXPECT_EQ(camera.wait_frame(0ns).status, FrameStatus::kComplete);
  EXPECT_EQ(camera.wait_frame(0ns).status, FrameStatus::kCameraError);
  EXPECT_NE(camera.last_error().find("b.pgm"), std::string::npos) << camera.last_error();
  const Frame third = camera.wait_frame(0ns);
  EXPECT_EQ(third.status, FrameStatus::kComplete);
  EXPECT_EQ(testing::compare_to_pattern(third.image, 2, 7), "");
}

TEST_F(ReplayCameraTest, PreloadNamesAnUnreadableFileAtOpen) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 8, 8, PixelFormat::kMono8, 0), dir_ / "missing.pgm"};
  ReplayCamera camera(o);
  try {
    camera.open();
    FAIL() << "a missing file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.pgm"), std::string::npos) << e.what();
  }
  util::write_file_atomic(dir_ / "garbage.pgm", "P5\n8 8\n255\nshort");
  o.files = {dir_ / "garbage.pgm"};
  ReplayCamera garbage(o);
  EXPECT_THROW(garbage.open(), std::runtime_error);
}

TEST_F(ReplayCameraTest, PacedFramesComeNoEarlierThanTheirTime) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 8, 8, PixelFormat::kMono8, 0),
             write("b.pgm", 8, 8, PixelFormat::kMono8, 1),
             write("c.pgm", 8, 8, PixelFormat::kMono8, 2)};
  o.frame_rate_hz = 20.0;  // 50 ms
  ReplayCamera camera(o);
  camera.start();
  const std::int64_t t0 = util::monotonic_ns();
  ASSERT_TRUE(camera.wait_frame(1s).received);
  // Frame 1 is due 50 ms after start: a 1 ms wait ends without it.
  const Frame early = camera.wait_frame(1ms);
  EXPECT_FALSE(early.received);
  EXPECT_EQ(early.status, FrameStatus::kTimeout);
  ASSERT_TRUE(camera.wait_frame(1s).received);
  ASSERT_TRUE(camera.wait_frame(1s).received);
  EXPECT_GE(util::monotonic_ns() - t0, 100000000);  // frame 2 is due at 100 ms
  EXPECT_EQ(camera.counters().wait_timeouts, 1U);
}

TEST_F(ReplayCameraTest, ReopenStartsAgainFromTheFirstFile) {
  ReplayCameraOptions o;
  o.files = {write("a.pgm", 8, 8, PixelFormat::kMono8, 0),
             write("b.pgm", 8, 8, PixelFormat::kMono8, 1)};
  o.paced = false;
  ReplayCamera camera(o);
  camera.start();
  camera.wait_frame(0ns);
  camera.wait_frame(0ns);
  EXPECT_TRUE(camera.finished());
  ASSERT_TRUE(camera.reopen());
  const Frame f = camera.wait_frame(0ns);
  ASSERT_EQ(f.status, FrameStatus::kComplete);
  EXPECT_TRUE(f.first_after_start);
  EXPECT_EQ(f.sequence, 2U);
  EXPECT_EQ(testing::compare_to_pattern(f.image, 0, 7), "");
  EXPECT_EQ(camera.counters().reopens, 1U);
}

TEST_F(ReplayCameraTest, NotStartedAndBadOptions) {
  ReplayCameraOptions o;
  EXPECT_THROW(ReplayCamera{o}, std::invalid_argument);
  o.files = {write("a.pgm", 8, 8, PixelFormat::kMono8, 0)};
  o.frame_rate_hz = -1;
  try {
    ReplayCamera camera(o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame_rate_hz = -1"), std::string::npos) << e.what();
  }
  o.frame_rate_hz = 100;
  ReplayCamera camera(o);
  const Frame f = camera.wait_frame(0ns);
  EXPECT_FALSE(f.received);
  EXPECT_EQ(f.status, FrameStatus::kCameraError);
}

}  // namespace
}  // namespace tactile::camera
