// The per-frame path allocates nothing (STYLE.md rule 4).
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "synthetic.hpp"
#include "tactile/extractor.hpp"

namespace tactile {
namespace {

TEST(Allocation, MeasureAllocatesNothing) {
  for (int depth : {8, 16}) {
    for (CentroidEstimator est : {CentroidEstimator::kPlain, CentroidEstimator::kThresholded,
                                  CentroidEstimator::kWindowed, CentroidEstimator::kGaussian}) {
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

TEST(Allocation, CounterSeesAllocations) {
  // The counter itself works: otherwise the test above proves nothing.
  testing::AllocationScope scope;
  auto* v = new std::vector<int>(100);
  delete v;
  EXPECT_GE(scope.count(), 2U);
}

}  // namespace
}  // namespace tactile
