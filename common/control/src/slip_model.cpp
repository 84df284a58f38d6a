#include <cstdint>
#include <vector>

#include "tactile/control/slip_detector.hpp"

// The learned detector's compiled-in model (docs/slip.md, "The learned combiner"), as the one
// model type (ObliviousForest) slip_train fits and scores too.
namespace tactile::control {

namespace {

// The compiled-in models of the learned detector (slip_train writes them): one trained under the
// paper's grip, one on light contacts too, for the margin grip (docs/slip.md, "One model per
// grip").
namespace paper_grip {
#include "slip_model.inc"
}  // namespace paper_grip
namespace margin_grip {
#include "slip_model_margin.inc"
}  // namespace margin_grip

static_assert(paper_grip::kSlipModel.features == kSlipFeatures &&
                  margin_grip::kSlipModel.features == kSlipFeatures,
              "a slip model was trained on another feature set: run slip_train again");
static_assert(paper_grip::kSlipModel.depth >= 1 && paper_grip::kSlipModel.depth <= 8 &&
                  margin_grip::kSlipModel.depth >= 1 && margin_grip::kSlipModel.depth <= 8,
              "slip_train fits depths 1 to 8");

template <typename T, std::size_t N>
std::vector<T> as_vector(const T (&a)[N], std::size_t n) {
  return std::vector<T>(a, a + n);
}

// Built at start-up, before the first frame; its scoring allocates nothing.
template <typename Info, std::size_t F, std::size_t T, std::size_t L>
ObliviousForest build(const Info& info, const std::uint8_t (&feature)[F],
                      const float (&threshold)[T], const float (&leaf)[L]) {
  return ObliviousForest(
      info.features, info.depth, info.base, as_vector(feature, info.trees * info.depth),
      as_vector(threshold, info.trees * info.depth), as_vector(leaf, info.trees << info.depth));
}

const ObliviousForest kPaperModel =
    build(paper_grip::kSlipModel, paper_grip::kSlipModelFeature, paper_grip::kSlipModelThreshold,
          paper_grip::kSlipModelLeaf);
const ObliviousForest kMarginModel =
    build(margin_grip::kSlipModel, margin_grip::kSlipModelFeature, margin_grip::kSlipModelThreshold,
          margin_grip::kSlipModelLeaf);

}  // namespace

const ObliviousForest& SlipDetector::model(GripKind grip) noexcept {
  return grip == GripKind::kMargin ? kMarginModel : kPaperModel;
}

double SlipDetector::model_decision(GripKind grip) noexcept {
  const double level = grip == GripKind::kMargin ? margin_grip::kSlipModel.decision
                                                 : paper_grip::kSlipModel.decision;
  return static_cast<double>(static_cast<float>(level));
}

}  // namespace tactile::control
