#include <cstdint>
#include <vector>

#include "tactile/control/slip_detector.hpp"

// The learned detector's compiled-in model (docs/slip.md, "The learned combiner"), as the one
// model type (ObliviousForest) slip_train fits and scores too.
namespace tactile::control {

namespace {

// The compiled-in model of the learned detector (slip_train writes it).
#include "slip_model.inc"

static_assert(kSlipModel.features == kSlipFeatures,
              "slip_model.inc was trained on another feature set: run slip_train again");
static_assert(kSlipModel.depth >= 1 && kSlipModel.depth <= 8, "slip_train fits depths 1 to 8");

template <typename T, std::size_t N>
std::vector<T> as_vector(const T (&a)[N], std::size_t n) {
  return std::vector<T>(a, a + n);
}

// Built at start-up, before the first frame; its scoring allocates nothing.
const ObliviousForest kModel(kSlipModel.features, kSlipModel.depth, kSlipModel.base,
                             as_vector(kSlipModelFeature, kSlipModel.trees* kSlipModel.depth),
                             as_vector(kSlipModelThreshold, kSlipModel.trees* kSlipModel.depth),
                             as_vector(kSlipModelLeaf, kSlipModel.trees << kSlipModel.depth));

}  // namespace

const ObliviousForest& SlipDetector::model() noexcept {
  return kModel;
}

double SlipDetector::model_decision() noexcept {
  return static_cast<double>(static_cast<float>(kSlipModel.decision));
}

}  // namespace tactile::control
