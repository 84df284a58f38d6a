// The per-frame path allocates nothing (docs/architecture.md, rule 4): wait_frame,
// release_frame and counters of a started camera. Counts operator new on the calling thread;
// Aravis's own threads and GLib's allocator are outside what this proves.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "alloc_counter.hpp"
#include "support/test_images.hpp"
#include "tactile/camera/aravis_camera.hpp"
#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/camera/replay_camera.hpp"
#include "tactile/util/pgm.hpp"

namespace tactile::camera {
namespace {

using namespace std::chrono_literals;

TEST(Allocation, AravisCameraWaitFrameAllocatesNothing) {
  FakeGvCameraOptions fo;
  fo.address = "127.0.0.2";
  fo.serial = "ALLOC";
  fo.width = 320;
  fo.height = 240;
  fo.frame_rate_hz = 200.0;
  FakeGvCamera fake(fo);
  Image image(320, 240, PixelFormat::kMono8);
  testing::render_pattern(image, 0, 1);
  ASSERT_TRUE(fake.publish(image.view(), 0, 1000));

  AravisCameraOptions o;
  o.camera = "127.0.0.2";
  o.width = 320;
  o.height = 240;
  o.frame_rate_hz = 200.0;
  AravisCamera camera(o);
  camera.start();
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(camera.wait_frame(2s).received);

  int complete = 0;
  std::size_t allocations = 0;
  {
    tactile::testing::AllocationScope scope;
    for (int i = 0; i < 40; ++i) {
      const Frame f = camera.wait_frame(2s);
      if (f.status == FrameStatus::kComplete && f.image.at(3, 2) == image.get(3, 2)) ++complete;
      if (i % 2 == 0) camera.release_frame();
      const CameraCounters c = camera.counters();
      if (c.frames == 0) ++complete;  // keeps the call; never true here
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(complete, 40);
  // Timeouts too: the wait that finds nothing allocates nothing either.
  camera.stop();
  camera.start();
  fake.set_gvsp_lost_ratio(1.0);
  while (camera.wait_frame(50ms).received) {
  }
  {
    tactile::testing::AllocationScope scope;
    const Frame f = camera.wait_frame(20ms);
    EXPECT_FALSE(f.received);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
}

TEST(Allocation, PreloadedReplayCameraAllocatesNothing) {
  std::string pattern = (std::filesystem::temp_directory_path() / "tactile_alloc_XXXXXX").string();
  ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
  const std::filesystem::path dir = pattern;
  ReplayCameraOptions o;
  for (int k = 0; k < 3; ++k) {
    Image image(64, 48, PixelFormat::kMono16);
    testing::render_pattern(image, static_cast<std::uint64_t>(k), 2);
    o.files.push_back(dir / ("f" + std::to_string(k) + ".pgm"));
    util::write_pgm(o.files.back(), image.view());
  }
  o.paced = false;
  o.loop = true;
  ReplayCamera camera(o);
  camera.start();
  std::size_t allocations = 0;
  int complete = 0;
  {
    tactile::testing::AllocationScope scope;
    for (int i = 0; i < 30; ++i) {
      if (camera.wait_frame(0ns).status == FrameStatus::kComplete) ++complete;
    }
    allocations = scope.count();
  }
  std::filesystem::remove_all(dir);
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(complete, 30);
}

TEST(Allocation, CounterSeesAllocations) {
  // The counter itself works: otherwise the tests above prove nothing.
  tactile::testing::AllocationScope scope;
  auto* text = new std::string(100, 'x');
  delete text;
  EXPECT_GE(scope.count(), 1U);
}

}  // namespace
}  // namespace tactile::camera
