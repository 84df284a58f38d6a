#pragma once

// Fitting gradient-boosted oblivious trees (control::ObliviousForest, the learned slip detector's
// model, docs/slip.md, "The learned combiner") for a binary label. Logistic loss, second-order leaf
// values with an L2 penalty, histogram splits on quantile bins. Pure and deterministic: the same
// rows give the same model on every machine (no threads, sums in row order).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "tactile/control/oblivious_forest.hpp"

namespace tactile::rig::train {

struct BoostParams {
  std::size_t trees = 64;
  std::size_t depth = 4;  // 1..8
  double learning_rate = 0.2;
  double l2 = 1.0;
  std::size_t bins = 32;  // 2..255
  // Rows taken per feature to place the bins' borders (quantiles), evenly spaced.
  std::size_t quantile_sample = 200000;
};

// Rows: `x` row-major (rows x features, at most control::kSlipFeatures features), `label` 0/1,
// `weight` > 0. Throws std::invalid_argument for inconsistent sizes, no rows, a single class or
// bad parameters. `progress` (optional) is
// called after each tree with the count done.
// The fitted model is the controller's own model type: slip_train scores it as the learned
// detector does.
control::ObliviousForest fit_boosted_trees(std::span<const float> x, std::size_t features,
                                           std::span<const std::uint8_t> label,
                                           std::span<const float> weight, const BoostParams& params,
                                           const std::function<void(std::size_t)>& progress = {});

// The fit's weights for rows that come from runs scored one by one (the sweep's precision and
// recall per run): run k's `run_rows[k]` rows, in order, scaled so that their total weight is the
// mean run's, within a factor `max_scale` either way. A run of no weight keeps its rows'.
std::vector<float> balance_runs(std::span<const float> weight,
                                std::span<const std::size_t> run_rows, double max_scale);

// The model as the C++ source slip_detector.cpp includes (slip_model.inc): `decision` is the
// score above which an element slips, `training` a line saying how it was made.
std::string model_source(const control::ObliviousForest& model, double decision,
                         const std::string& training);

}  // namespace tactile::rig::train
