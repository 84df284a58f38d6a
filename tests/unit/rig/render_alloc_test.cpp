// The per-step and per-frame paths of the rig allocate nothing (docs/architecture.md, rule 4).
#include <gtest/gtest.h>

#include <vector>

#include "alloc_counter.hpp"
#include "tactile/rig/optics.hpp"
#include "tactile/rig/scoring.hpp"
#include "tactile/rig/truth.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {
namespace {

class RigRenderAllocation : public ::testing::TestWithParam<ElementModel> {};

TEST_P(RigRenderAllocation, StepTruthAndRenderAllocateNothing) {
  World w{WorldParams{}};
  const auto normals = w.element_normals();
  const CameraParams cam;
  SensorOpticsParams opt;
  opt.element_model = GetParam();
  const Calibration cal = make_calibration("left", cam, opt, normals);
  Renderer r(cal, cam, opt, 2);
  TruthRecorder truth(0.04, 0.1);
  util::Random rng(4);
  Image img;
  std::vector<ElementLoad> loads(41);
  r.render(loads, rng, img);
  ArmCommand down;
  down.kind = CommandKind::kMoveTo;
  down.segment_id = 1;
  down.target_position_m = {0.35, -0.10, 0.01};
  down.max_speed_mps = 0.1;
  std::size_t count = 0;
  double grip_needed = 0;
  {
    testing::AllocationScope scope;
    w.apply(down);
    for (int frame = 0; frame < 20; ++frame) {
      for (int s = 0; s < 100; ++s)
        w.step(1e-4);
      const GroundTruth& gt = truth.take(w, static_cast<std::uint64_t>(frame), 0.004);
      grip_needed += grip_truth(w, gt).needed_n;
      for (std::size_t k = 0; k < loads.size(); ++k)
        loads[k] = {gt.fingertips[0].elements[k].fz_n + 0.1 * frame, 0.001 * frame, 0.0};
      r.render(loads, rng, img);
    }
    count = scope.count();
  }
  EXPECT_EQ(count, 0U);
  EXPECT_GT(grip_needed, 0.0);
}

INSTANTIATE_TEST_SUITE_P(ElementModels, RigRenderAllocation,
                         ::testing::Values(ElementModel::kGaussian, ElementModel::kFeelers));

// The grip's record of each frame (the report's `grip`) allocates nothing once reserved.
TEST(RigAllocation, GripScorerAddAllocatesNothingAfterReserve) {
  World w{WorldParams{}};
  TruthRecorder truth(0.04, 0.1);
  GripScorer s;
  s.reserve(500);
  std::size_t count = 0;
  {
    testing::AllocationScope scope;
    for (int frame = 0; frame < 500; ++frame) {
      w.step(1e-3);
      s.add(w.time(), grip_truth(w, truth.take(w, static_cast<std::uint64_t>(frame), 0.004)));
    }
    count = scope.count();
  }
  EXPECT_EQ(count, 0U);
  EXPECT_EQ(s.finish().held_frames, 0U);  // the fingers never closed
}

}  // namespace
}  // namespace tactile::rig
