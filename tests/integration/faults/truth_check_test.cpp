// The check the packet-loss tests rely on, tried on frames made here: it passes frames measured
// from their true images, and it catches each fault it exists to catch (a frame with one stale
// packet measured as whole, a displacement across a gap, readings on an incomplete frame).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "fault_support.hpp"
#include "sensor_config.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::faults {
namespace {

// GVSP data bytes in one 65000-byte packet (IP, UDP and GVSP headers taken off).
constexpr std::size_t kPacketData = 65000 - 20 - 8 - 8;

// What sensor_node publishes for a stream of camera frames, made here with the same core.
class FakeSensorNode {
 public:
  explicit FakeSensorNode(const KnownImages& images, ExtractorOptions options)
      : images_(images), cal_(fault_calibration("left")), extractor_(cal_, options) {
    extractor_.begin_reference();
    (void)extractor_.add_reference_frame(images.background().view());
    (void)extractor_.finish_reference();
  }
  const Calibration& calibration() const { return cal_; }

  // Camera frame k arrives whole; `pixels` is what the receiver holds (the true image unless
  // a test says otherwise).
  void whole(std::uint64_t k, const Image* pixels = nullptr) {
    const Image& image = pixels != nullptr ? *pixels : images_.image(k);
    (void)extractor_.measure(image.view(), {k, images_.code().encode(k)});
    push(k, v1::FRAME_STATUS_COMPLETE);
  }
  void incomplete(std::uint64_t k) { push(k, v1::FRAME_STATUS_MISSING_PACKETS); }
  std::vector<v1::TactileFrame>& frames() { return frames_; }

 private:
  void push(std::uint64_t k, v1::FrameStatus status) {
    wire::FrameHeader h;
    h.sequence = frames_.size();
    h.camera_frame_id = 100 + k;
    h.camera_timestamp_ns = images_.code().encode(k);
    h.status = status;
    h.frames_skipped = static_cast<std::uint32_t>(have_last_ && k > last_ + 1 ? k - last_ - 1 : 0);
    have_last_ = true;
    last_ = k;
    frames_.emplace_back();
    wire::fill_tactile_frame(cal_.sensor_id, h, extractor_.readings(), cal_.mm_per_px,
                             frames_.back());
  }

  const KnownImages& images_;
  Calibration cal_;
  Extractor extractor_;
  std::vector<v1::TactileFrame> frames_;
  bool have_last_ = false;
  std::uint64_t last_ = 0;
};

class TruthCheck : public ::testing::Test {
 protected:
  TruthReport check(FakeSensorNode& node) const {
    return check_against_truth(node.frames(), known_images_truth(images_), images_.background(),
                               node.calibration(), options_);
  }
  const KnownImages images_{fault_calibration("left"), 50};
  const ExtractorOptions options_ = sensor::default_sensor_config().measurement;
};

TEST_F(TruthCheck, PassesFramesMeasuredFromTheirTrueImages) {
  FakeSensorNode node(images_, options_);
  for (std::uint64_t k = 0; k < 40; ++k) {
    if (k % 9 == 4) {
      node.incomplete(k);
    } else if (k % 13 != 7) {  // k % 13 == 7: lost altogether
      node.whole(k);
    }
  }
  const TruthReport r = check(node);
  EXPECT_TRUE(r.failures.empty()) << describe(r);
  EXPECT_EQ(r.incomplete, 4U) << describe(r);
  EXPECT_EQ(r.never_received, 3U) << describe(r);
  EXPECT_GT(r.complete_after_gap, 0U) << describe(r);
  EXPECT_GT(r.displacements_measured, 0U) << describe(r);
  EXPECT_EQ(r.displacements_after_gap, 0U) << describe(r);
}

TEST_F(TruthCheck, CatchesAFrameWithOneStalePacketMeasuredAsWhole) {
  // An incomplete frame keeps, where packets are missing, what its buffer held before: the
  // frame of a few periods earlier (the receiver cycles through a pool of buffers). Whichever
  // single data packet is stale, the readings differ from the true image's.
  const Image& truth = images_.image(20);
  const Image& before = images_.image(14);
  const std::size_t bytes = truth.bytes().size();
  for (std::size_t begin = 0; begin < bytes; begin += kPacketData) {
    const std::size_t end = std::min(bytes, begin + kPacketData);
    Image mixed = truth;
    std::memcpy(mixed.bytes().data() + begin, before.bytes().data() + begin, end - begin);
    FakeSensorNode node(images_, options_);
    node.whole(19);
    node.whole(20, &mixed);
    node.whole(21);
    const TruthReport r = check(node);
    EXPECT_FALSE(r.failures.empty()) << "stale bytes " << begin << ".." << end << " not caught";
  }
}

TEST_F(TruthCheck, CatchesADisplacementAcrossAGap) {
  ExtractorOptions lenient = options_;
  lenient.max_gap_frames = 4;  // what sensor_node must not do
  FakeSensorNode node(images_, lenient);
  node.whole(0);
  node.whole(1);
  node.incomplete(2);
  node.whole(3);
  const TruthReport r = check(node);
  EXPECT_GT(r.displacements_after_gap, 0U) << describe(r);
  EXPECT_FALSE(r.failures.empty()) << describe(r);
}

TEST_F(TruthCheck, CatchesReadingsOnAnIncompleteFrame) {
  FakeSensorNode node(images_, options_);
  node.whole(0);
  node.whole(1);
  node.frames().back().set_status(v1::FRAME_STATUS_MISSING_PACKETS);
  const TruthReport r = check(node);
  EXPECT_FALSE(r.failures.empty()) << describe(r);
}

}  // namespace
}  // namespace tactile::faults
