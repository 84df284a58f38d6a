#include "tactile/rig/boosted_trees.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tactile::rig::train {

namespace {

// The bins' borders of one feature: distinct quantiles of an evenly spaced sample of its values.
std::vector<float> borders_of(std::span<const float> x, std::size_t features, std::size_t f,
                              std::size_t rows, const BoostParams& p) {
  const std::size_t take = std::min(rows, p.quantile_sample);
  std::vector<float> v;
  v.reserve(take);
  for (std::size_t k = 0; k < take; ++k) {
    const std::size_t r = k * rows / take;
    v.push_back(x[r * features + f]);
  }
  std::sort(v.begin(), v.end());
  std::vector<float> b;
  for (std::size_t q = 1; q < p.bins; ++q) {
    const float value = v[q * (v.size() - 1) / p.bins];
    if (b.empty() || value > b.back()) b.push_back(value);
  }
  // A border at the largest value splits nothing off.
  while (!b.empty() && !(v.back() > b.back()))
    b.pop_back();
  return b;
}

}  // namespace

control::ObliviousForest fit_boosted_trees(std::span<const float> x, std::size_t features,
                                           std::span<const std::uint8_t> label,
                                           std::span<const float> weight, const BoostParams& p,
                                           const std::function<void(std::size_t)>& progress) {
  if (features == 0 || features > control::kSlipFeatures)
    throw std::invalid_argument(
        fmt::format("features must be 1..{}, got {}", control::kSlipFeatures, features));
  const std::size_t rows = label.size();
  if (rows == 0) throw std::invalid_argument("no training rows");
  if (x.size() != rows * features || weight.size() != rows)
    throw std::invalid_argument("rows, labels and weights differ in number");
  if (p.depth < 1 || p.depth > 8) throw std::invalid_argument("depth must be 1..8");
  if (p.bins < 2 || p.bins > 255) throw std::invalid_argument("bins must be 2..255");
  if (!(p.learning_rate > 0) || !(p.l2 >= 0)) throw std::invalid_argument("bad learning rate/l2");
  double wpos = 0, wneg = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    if (!(weight[r] > 0) || !std::isfinite(weight[r]))
      throw std::invalid_argument(fmt::format("row {}: weight must be positive", r));
    (label[r] != 0 ? wpos : wneg) += static_cast<double>(weight[r]);
  }
  if (wpos == 0 || wneg == 0) throw std::invalid_argument("the labels hold a single class");

  // Quantile bins, stored feature-major: bin = the number of borders the value exceeds.
  std::vector<std::vector<float>> borders(features);
  std::vector<std::uint8_t> bin(rows * features);
  for (std::size_t f = 0; f < features; ++f) {
    borders[f] = borders_of(x, features, f, rows, p);
    const auto& b = borders[f];
    std::uint8_t* out = &bin[f * rows];
    for (std::size_t r = 0; r < rows; ++r) {
      const float v = x[r * features + f];
      out[r] = static_cast<std::uint8_t>(std::lower_bound(b.begin(), b.end(), v) - b.begin());
    }
  }

  const double base = std::log(wpos / wneg);
  std::vector<std::uint8_t> split_feature;
  std::vector<float> split_threshold, leaf;
  std::vector<double> score(rows, base), g(rows), h(rows);
  std::vector<std::uint16_t> node(rows);
  const std::size_t leaves = std::size_t{1} << p.depth;
  const std::size_t nb = p.bins;
  std::vector<double> hg(leaves * nb), hh(leaves * nb);
  for (std::size_t t = 0; t < p.trees; ++t) {
    for (std::size_t r = 0; r < rows; ++r) {
      const double q = 1.0 / (1.0 + std::exp(-score[r]));
      const auto w = static_cast<double>(weight[r]);
      g[r] = w * (q - (label[r] != 0 ? 1.0 : 0.0));
      h[r] = w * std::max(q * (1.0 - q), 1e-6);
      node[r] = 0;
    }
    for (std::size_t d = 0; d < p.depth; ++d) {
      const std::size_t nodes = std::size_t{1} << d;
      double best_gain = -1;
      std::size_t best_f = 0, best_split = 0;
      for (std::size_t f = 0; f < features; ++f) {
        const std::size_t splits = borders[f].size();
        if (splits == 0) continue;
        std::fill(hg.begin(), hg.begin() + static_cast<std::ptrdiff_t>(nodes * nb), 0.0);
        std::fill(hh.begin(), hh.begin() + static_cast<std::ptrdiff_t>(nodes * nb), 0.0);
        const std::uint8_t* fb = &bin[f * rows];
        for (std::size_t r = 0; r < rows; ++r) {
          const std::size_t k = node[r] * nb + fb[r];
          hg[k] += g[r];
          hh[k] += h[r];
        }
        // Split j sends bins > j to the right, at every node alike; a split this tree made
        // already at a shallower depth separates nothing more.
        for (std::size_t j = 0; j < splits; ++j) {
          bool used = false;
          for (std::size_t e = 0; e < d; ++e) {
            const std::size_t k = t * p.depth + e;
            used = used || (split_feature[k] == f && split_threshold[k] == borders[f][j]);
          }
          if (used) continue;
          double gain = 0;
          for (std::size_t n = 0; n < nodes; ++n) {
            double gl = 0, hl = 0, gt = 0, ht = 0;
            for (std::size_t b = 0; b <= splits; ++b) {
              gt += hg[n * nb + b];
              ht += hh[n * nb + b];
              if (b <= j) {
                gl += hg[n * nb + b];
                hl += hh[n * nb + b];
              }
            }
            const double gr = gt - gl, hr = ht - hl;
            gain += gl * gl / (hl + p.l2) + gr * gr / (hr + p.l2) - gt * gt / (ht + p.l2);
          }
          if (gain > best_gain) {
            best_gain = gain;
            best_f = f;
            best_split = j;
          }
        }
      }
      split_feature.push_back(static_cast<std::uint8_t>(best_f));
      split_threshold.push_back(borders[best_f].empty() ? 0.0f : borders[best_f][best_split]);
      const std::uint8_t* fb = &bin[best_f * rows];
      for (std::size_t r = 0; r < rows; ++r) {
        if (fb[r] > best_split) node[r] = static_cast<std::uint16_t>(node[r] | (1u << d));
      }
    }
    std::vector<double> lg(leaves, 0.0), lh(leaves, 0.0);
    for (std::size_t r = 0; r < rows; ++r) {
      lg[node[r]] += g[r];
      lh[node[r]] += h[r];
    }
    std::vector<float> value(leaves);
    for (std::size_t l = 0; l < leaves; ++l)
      value[l] = static_cast<float>(-p.learning_rate * lg[l] / (lh[l] + p.l2));
    leaf.insert(leaf.end(), value.begin(), value.end());
    for (std::size_t r = 0; r < rows; ++r)
      score[r] += static_cast<double>(value[node[r]]);
    if (progress) progress(t + 1);
  }
  return control::ObliviousForest(features, p.depth, base, std::move(split_feature),
                                  std::move(split_threshold), std::move(leaf));
}

std::vector<float> balance_runs(std::span<const float> weight,
                                std::span<const std::size_t> run_rows, double max_scale) {
  std::size_t rows = 0;
  for (const std::size_t n : run_rows)
    rows += n;
  if (rows != weight.size())
    throw std::invalid_argument("balance_runs: the runs' rows do not add up to the weights'");
  if (!(max_scale >= 1.0)) throw std::invalid_argument("balance_runs: max_scale must be >= 1");
  std::vector<double> sums(run_rows.size(), 0.0);
  double total = 0;
  for (std::size_t k = 0, at = 0; k < run_rows.size(); ++k) {
    for (std::size_t n = 0; n < run_rows[k]; ++n, ++at)
      sums[k] += static_cast<double>(weight[at]);
    total += sums[k];
  }
  const double mean = run_rows.empty() ? 0.0 : total / static_cast<double>(run_rows.size());
  std::vector<float> out(weight.begin(), weight.end());
  for (std::size_t k = 0, at = 0; k < run_rows.size(); ++k) {
    const double scale = sums[k] > 0 ? std::clamp(mean / sums[k], 1.0 / max_scale, max_scale) : 1.0;
    for (std::size_t n = 0; n < run_rows[k]; ++n, ++at)
      out[at] = static_cast<float>(static_cast<double>(weight[at]) * scale);
  }
  return out;
}

std::string model_source(const control::ObliviousForest& m, double decision,
                         const std::string& training) {
  std::string s;
  s +=
      "// The learned slip detector's model (docs/slip.md, \"The learned combiner\"). Written by\n";
  s += "// slip_train; do not edit. " + training + "\n";
  s += "// clang-format off\n";
  s += "struct SlipModelInfo {\n  std::size_t features;\n  std::size_t trees;\n"
       "  std::size_t depth;\n  double base;\n  double decision;\n  const char* training;\n};\n";
  std::string quoted;
  for (const char c : training) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  s += fmt::format(
      "inline constexpr SlipModelInfo kSlipModel{{{}, {}, {}, {:.17g}, {:.17g},\n    \"{}\"}};\n",
      m.features(), m.trees(), m.depth(), m.base(), decision, quoted);
  const auto list = [&](const char* decl, std::size_t n, const auto& at) {
    s += fmt::format("inline constexpr {}[{}] = {{", decl, std::max<std::size_t>(n, 1));
    for (std::size_t k = 0; k < n; ++k)
      s += fmt::format("{}{}", k % 8 == 0 ? "\n    " : " ", at(k));
    if (n == 0) s += "0";
    s += "};\n";
  };
  list("std::uint8_t kSlipModelFeature", m.feature().size(),
       [&](std::size_t k) { return fmt::format("{},", m.feature()[k]); });
  list("float kSlipModelThreshold", m.threshold().size(),
       [&](std::size_t k) { return fmt::format("{:#.9g}f,", m.threshold()[k]); });
  list("float kSlipModelLeaf", m.leaf().size(),
       [&](std::size_t k) { return fmt::format("{:#.9g}f,", m.leaf()[k]); });
  s += "// clang-format on\n";
  return s;
}

}  // namespace tactile::rig::train
