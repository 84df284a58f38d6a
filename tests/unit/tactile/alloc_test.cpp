// The per-frame path allocates nothing (docs/architecture.md, rule 4).
#include <gtest/gtest.h>

#include <algorithm>

#include "alloc_counter.hpp"
#include "synthetic.hpp"
#include "tactile/extractor.hpp"

namespace tactile {
namespace {

TEST(Allocation, MeasureAllocatesNothing) {
  for (int depth : {8, 16}) {
    for (CentroidEstimator est :
         {CentroidEstimator::kPlain, CentroidEstimator::kThresholded, CentroidEstimator::kWindowed,
          CentroidEstimator::kGaussian, CentroidEstimator::kGaussianAxes}) {
      testing::SceneOptions o;
      o.bit_depth = depth;
      const Calibration cal = testing::grid_calibration(o, 8, 5, 60, 14);
      ExtractorOptions opt;
      opt.estimator = est;
      opt.reference_frames = 2;
      Extractor ex(cal, opt);
      util::Random rng(7);
      Image frame;
      testing::render(o, {}, rng, frame);
      ex.add_reference_frame(frame.view());
      testing::render(o, {}, rng, frame);
      ASSERT_EQ(ex.add_reference_frame(frame.view()).status, ReferenceStatus::kComplete);

      std::vector<testing::Spot> spots;
      for (std::size_t i = 0; i < cal.elements.size(); i += 2) {
        spots.push_back({cal.elements[i].center_px + Vec2{0.3, -0.2}, 90, 2.5});
      }
      std::vector<Image> frames(3);
      for (auto& f : frames)
        testing::render(o, spots, rng, f);

      std::size_t allocations = 0;
      {
        testing::AllocationScope scope;
        for (std::uint64_t seq = 0; seq < 30; ++seq) {
          ex.measure(frames[seq % 3].view(), {seq, static_cast<std::int64_t>(seq) * 10000000});
        }
        allocations = scope.count();
      }
      EXPECT_EQ(allocations, 0U) << "depth " << depth << " estimator " << to_string(est);
      EXPECT_TRUE(ex.readings()[0].contact);
    }
  }
}

// Every path of the fast per-frame code: both kernel sets, whole frames and regions of interest,
// elements entering and leaving contact (the out-of-contact exact-G pass and the moments pass),
// kGaussian's second pass, repeated and jumping sequence numbers, wrong frames.
TEST(Allocation, EveryPerFramePathAllocatesNothing) {
  for (int depth : {8, 16}) {
    testing::SceneOptions o;
    o.bit_depth = depth;
    const Calibration cal = testing::grid_calibration(o, 8, 5, 60, 14);
    const testing::SceneRenderer renderer(o, &cal);
    util::Random rng(11);
    std::vector<Image> reference(2);
    for (Image& r : reference)
      renderer.render({}, rng, r);
    // Frames with spots of changing width and brightness on changing elements, and a frame
    // without spots.
    std::vector<Image> frames(6);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      std::vector<testing::Spot> spots;
      for (std::size_t i = k % 3; i < cal.elements.size(); i += 1 + k % 3) {
        spots.push_back({cal.elements[i].center_px + Vec2{0.4, -0.3},
                         k == 2 ? 0.0 : 40.0 + 20.0 * static_cast<double>(k),
                         1.0 + static_cast<double>(k)});
      }
      renderer.render(spots, rng, frames[k]);
    }
    const Region roi = region_of_interest(cal);
    const Image wrong(100, 100, frames[0].format());  // holds no disk: refused
    for (bool portable : {false, true}) {
      for (CentroidEstimator est : {CentroidEstimator::kPlain, CentroidEstimator::kThresholded,
                                    CentroidEstimator::kWindowed, CentroidEstimator::kGaussian,
                                    CentroidEstimator::kGaussianAxes}) {
        ExtractorOptions opt;
        opt.estimator = est;
        opt.reference_frames = 2;
        opt.portable_kernels = portable;
        opt.accept_regions = true;
        Extractor ex(cal, opt);
        ex.add_reference_frame(reference[0].view());
        ASSERT_EQ(ex.add_reference_frame(reference[1].view()).status, ReferenceStatus::kComplete);

        std::size_t allocations = 0;
        {
          testing::AllocationScope scope;
          const std::uint64_t seqs[] = {0, 1, 2, 2, 1, 5, 6, 40, 41, 42, 43, 44};
          for (std::size_t n = 0; n < 36; ++n) {
            ImageView v = frames[n % frames.size()].view();
            if (n % 4 == 3) {
              // The region of interest, as a view into the whole frame's rows.
              v.data += static_cast<std::size_t>(roi.y) * v.stride_bytes +
                        static_cast<std::size_t>(roi.x) * bytes_per_pixel(v.format);
              v.width = roi.width;
              v.height = roi.height;
              v.origin_x = roi.x;
              v.origin_y = roi.y;
            }
            ex.measure(v, {seqs[n % 12] + 100 * (n / 12), 0});
          }
          ex.measure(wrong.view(), {1000, 0});
          ex.forget_previous();
          allocations = scope.count();
        }
        EXPECT_EQ(allocations, 0U) << "depth " << depth << " estimator " << to_string(est)
                                   << (portable ? " portable" : "");
        // The paths ran: the last whole frame had spots in contact.
        EXPECT_TRUE(std::any_of(ex.readings().begin(), ex.readings().end(),
                                [](const ElementReading& r) { return r.contact; }));
      }
    }
  }
}

TEST(Allocation, CounterSeesAllocations) {
  // The counter itself works: otherwise the test above proves nothing.
  testing::AllocationScope scope;
  auto* v = new std::vector<int>(100);
  delete v;
  EXPECT_GE(scope.count(), 2U);
}

}  // namespace
}  // namespace tactile
