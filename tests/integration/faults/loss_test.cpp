// Packet loss on the camera link, with real GigE Vision packets: sensor_node (a child process)
// receives from a fake camera that drops stream packets (the rig's in-process camera with
// gvsp-lost-ratio, or arv-fake-gv-camera-0.8 -r), or from a camera whose packets nft drops in
// this test's own network namespace. Every published frame is checked against the image the
// camera was given: an incomplete frame is never measured as whole, a whole frame's readings are
// exactly those of its true image, and displacement spans only consecutive whole frames.
#include <gtest/gtest.h>

#include "fault_support.hpp"
#include "loss_expectations.hpp"

namespace tactile::faults {
namespace {

class InProcessCameraLoss : public ::testing::TestWithParam<int> {};

TEST_P(InProcessCameraLoss, IncompleteFramesAreReportedAndNeverMeasured) {
  LossSetup setup;
  setup.gvsp_lost_ratio = GetParam() / 1000.0;
  setup.frames = 300;
  const LossRun run = run_sensor_node_under_loss(TACTILE_SENSOR_NODE_PATH, setup);
  expect_loss_handled(run);
  // The camera sent at least every frame sensor_node published.
  EXPECT_GE(run.frames_sent, run.truth.frames);
  RecordProperty("complete", static_cast<int>(run.truth.complete));
  RecordProperty("incomplete", static_cast<int>(run.truth.incomplete));
  RecordProperty("lost", static_cast<int>(run.truth.frames_lost));
  std::printf("gvsp-lost-ratio %.1f %%: %s\n", GetParam() / 10.0, describe(run.truth).c_str());
}

INSTANTIATE_TEST_SUITE_P(PerThousand, InProcessCameraLoss, ::testing::Values(5, 20, 50),
                         [](const auto& p) { return std::to_string(p.param) + "_per_thousand"; });

TEST(NftLoss, OnePercentOfTheCamerasPacketsDropped) {
  LossSetup setup;
  setup.nft_percent = 1;
  setup.frames = 300;
  const LossRun run = run_sensor_node_under_loss(TACTILE_SENSOR_NODE_PATH, setup);
  expect_loss_handled(run);
  // nft did drop about 1 % of what the camera sent (7 packets a frame: some 2100 packets).
  EXPECT_GT(run.nft.sent, 1000U) << describe(run);
  EXPECT_GT(run.nft.dropped, 0U) << describe(run);
  EXPECT_LT(run.nft.dropped * 100, run.nft.sent * 3) << describe(run);
  std::printf("nft 1 %%: dropped %llu of %llu packets; %s\n",
              static_cast<unsigned long long>(run.nft.dropped),
              static_cast<unsigned long long>(run.nft.sent), describe(run.truth).c_str());
}

TEST(ArvFakeCameraProcessLoss, TwoPercentOfItsStreamPacketsDropped) {
  LossSetup setup;
  setup.arv_per_thousand = 20;
  setup.frames = 300;
  const LossRun run = run_sensor_node_under_loss(TACTILE_SENSOR_NODE_PATH, setup);
  expect_loss_handled(run);
  std::printf("arv-fake-gv-camera-0.8 -r 20: %s\n", describe(run.truth).c_str());
}

}  // namespace
}  // namespace tactile::faults
