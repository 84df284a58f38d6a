// The learned slip detector's trainer (docs/slip.md, "The learned combiner"): boosted oblivious
// trees learn a known rule, deterministically, and slip_train writes a model from real runs that
// does not depend on how many runs went at once.
#include "tactile/rig/boosted_trees.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "process.hpp"
#include "tactile/util/files.hpp"

namespace tactile::rig::train {
namespace {

// Rows of 3 features uniform in [0, 1); the label: x0 > 0.3 and x1 > 0.6 (x2 is noise), with
// `flip` of the labels flipped at random.
struct Data {
  std::vector<float> x;
  std::vector<std::uint8_t> y;
  std::vector<float> w;
};
Data make(std::size_t rows, double flip, unsigned seed) {
  Data d;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (std::size_t r = 0; r < rows; ++r) {
    const float a = u(rng), b = u(rng), c = u(rng);
    d.x.insert(d.x.end(), {a, b, c});
    bool label = a > 0.3f && b > 0.6f;
    if (static_cast<double>(u(rng)) < flip) label = !label;
    d.y.push_back(label ? 1 : 0);
    d.w.push_back(1.0f);
  }
  return d;
}

TEST(BoostedTrees, LearnsAConjunctionOfThresholds) {
  const Data train = make(20000, 0.02, 1);
  BoostParams p;
  p.trees = 40;
  p.depth = 2;
  const control::ObliviousForest m = fit_boosted_trees(train.x, 3, train.y, train.w, p);
  ASSERT_EQ(m.trees(), 40U);
  const Data test = make(5000, 0.0, 2);
  std::size_t right = 0;
  for (std::size_t r = 0; r < test.y.size(); ++r) {
    const bool p_slip = m.score({&test.x[r * 3], 3}) > 0;
    right += p_slip == (test.y[r] != 0) ? 1 : 0;
  }
  // The bins' borders sit within 1/32 of the true thresholds.
  EXPECT_GT(static_cast<double>(right) / static_cast<double>(test.y.size()), 0.97);
  // The first trees split on the rule's features first, not on the noise (late trees may fit
  // the flipped labels).
  for (std::size_t t = 0; t < 10; ++t)
    EXPECT_NE(m.feature()[t * m.depth()], 2U) << "tree " << t;
}

TEST(BoostedTrees, WeightsCountAsRepeatedRows) {
  // One row of weight 3 scores like the same row three times.
  const Data d = make(3000, 0.05, 3);
  Data once = d, thrice = d;
  once.w[0] = 3.0f;
  for (int k = 0; k < 2; ++k) {
    thrice.x.insert(thrice.x.end(), d.x.begin(), d.x.begin() + 3);
    thrice.y.push_back(d.y[0]);
    thrice.w.push_back(1.0f);
  }
  BoostParams p;
  p.trees = 5;
  p.quantile_sample = 1;  // the same borders for both
  const control::ObliviousForest a = fit_boosted_trees(once.x, 3, once.y, once.w, p);
  const control::ObliviousForest b = fit_boosted_trees(thrice.x, 3, thrice.y, thrice.w, p);
  for (std::size_t r = 0; r < 50; ++r)
    EXPECT_NEAR(a.score({&d.x[r * 3], 3}), b.score({&d.x[r * 3], 3}), 1e-4);
}

TEST(BoostedTrees, RefusesBadInput) {
  const Data d = make(100, 0.0, 4);
  BoostParams p;
  EXPECT_THROW(fit_boosted_trees(d.x, 3, {}, {}, p), std::invalid_argument);
  EXPECT_THROW(fit_boosted_trees({d.x.data(), 10}, 3, d.y, d.w, p), std::invalid_argument);
  std::vector<std::uint8_t> one_class(d.y.size(), 0);
  EXPECT_THROW(fit_boosted_trees(d.x, 3, one_class, d.w, p), std::invalid_argument);
  std::vector<float> negative = d.w;
  negative[7] = -1.0f;
  EXPECT_THROW(fit_boosted_trees(d.x, 3, d.y, negative, p), std::invalid_argument);
  p.depth = 9;
  EXPECT_THROW(fit_boosted_trees(d.x, 3, d.y, d.w, p), std::invalid_argument);
}

TEST(BoostedTrees, SourceStatesEveryTreeAndTheDecision) {
  const Data d = make(2000, 0.0, 5);
  BoostParams p;
  p.trees = 3;
  p.depth = 2;
  const control::ObliviousForest m = fit_boosted_trees(d.x, 3, d.y, d.w, p);
  const std::string src = model_source(m, 0.5, "test \"model\"");
  EXPECT_NE(src.find("kSlipModel{3, 3, 2,"), std::string::npos) << src;
  EXPECT_NE(src.find("kSlipModelFeature[6]"), std::string::npos) << src;
  EXPECT_NE(src.find("kSlipModelThreshold[6]"), std::string::npos) << src;
  EXPECT_NE(src.find("kSlipModelLeaf[12]"), std::string::npos) << src;
  EXPECT_NE(src.find("\"test \\\"model\\\"\""), std::string::npos) << src;
}

// Each run weighs as much as the mean run, within the bound; the rows of one run keep their ratios.
TEST(BoostedTrees, BalanceRunsWeighsEachRunAsTheMeanRun) {
  // Run 0: 2 rows of 1; run 1: 6 rows, one of weight 8 (a kept easy row); run 2: no rows.
  const std::vector<float> w{1, 1, 1, 1, 1, 1, 1, 8};
  const std::vector<std::size_t> rows{2, 6, 0};
  // Totals 2 and 13; the mean over the three runs is 5.
  const std::vector<float> b = balance_runs(w, rows, 100.0);
  ASSERT_EQ(b.size(), w.size());
  EXPECT_FLOAT_EQ(b[0] + b[1], 5.0f);
  float second = 0;
  for (std::size_t i = 2; i < 8; ++i)
    second += b[i];
  EXPECT_FLOAT_EQ(second, 5.0f);
  EXPECT_FLOAT_EQ(b[7] / b[2], 8.0f);
  // Within a factor 2 either way: run 0 doubles, run 1 halves.
  const std::vector<float> c = balance_runs(w, rows, 2.0);
  EXPECT_FLOAT_EQ(c[0], 2.0f);
  EXPECT_FLOAT_EQ(c[2], 0.5f);
  EXPECT_FLOAT_EQ(c[7], 4.0f);
  EXPECT_THROW(balance_runs(w, std::vector<std::size_t>{2, 5}, 2.0), std::invalid_argument);
  EXPECT_THROW(balance_runs(w, rows, 0.5), std::invalid_argument);
}

// slip_train over real lockstep runs: two short runs of one seed, once with one thread and once
// with two, give the same file byte for byte.
TEST(SlipTrain, TheModelDoesNotDependOnTheJobs) {
  const testing::TempDir dir;
  const auto train = [&](const char* jobs, const std::string& out) {
    return testing::run({TACTILE_SLIP_TRAIN_PATH, "--seeds", "5", "--scenarios", "2", "--max-time",
                         "6", "--trees", "4", "--depth", "4", "--jobs", jobs, "--out", out},
                        std::chrono::seconds(120));
  };
  const std::string a = (dir.path() / "a.inc").string();
  const std::string b = (dir.path() / "b.inc").string();
  const auto ra = train("1", a);
  ASSERT_EQ(ra.exit_code, 0) << ra.err;
  const auto rb = train("2", b);
  ASSERT_EQ(rb.exit_code, 0) << rb.err;
  const std::string text = util::read_file(a);
  EXPECT_EQ(text, util::read_file(b));
  EXPECT_NE(text.find("kSlipModel{30, 4, 4,"), std::string::npos) << text;
  EXPECT_NE(ra.err.find("run 2/2"), std::string::npos) << ra.err;

  // With the model in the controller the runs go otherwise (its decisions steer them; in the
  // first 10 s of seed 7's two scenarios they log 17,031 rows with the field detector, 15,777
  // with the model), and the file says how it was trained.
  const auto rows = [](const std::string& err) {
    const std::size_t end = err.find(" rows (");
    const std::size_t start = err.rfind(' ', end - 1);
    return end == std::string::npos || start == std::string::npos
               ? std::string()
               : err.substr(start + 1, end - start - 1);
  };
  const auto steer = [&](const char* controller, const std::string& out) {
    return testing::run(
        {TACTILE_SLIP_TRAIN_PATH, "--seeds", "7", "--scenarios", "2", "--max-time", "10", "--trees",
         "4", "--depth", "4", "--controller", controller, "--out", out},
        std::chrono::seconds(120));
  };
  const std::string c = (dir.path() / "c.inc").string();
  const auto by_rules = steer("field", (dir.path() / "d.inc").string());
  ASSERT_EQ(by_rules.exit_code, 0) << by_rules.err;
  const auto by_model = steer("learned", c);
  ASSERT_EQ(by_model.exit_code, 0) << by_model.err;
  EXPECT_NE(rows(by_rules.err), "") << by_rules.err;
  EXPECT_NE(rows(by_model.err), rows(by_rules.err)) << by_model.err;
  const std::string steered = util::read_file(c);
  EXPECT_NE(steered.find("--controller learned"), std::string::npos) << steered;
  EXPECT_EQ(text.find("--controller"), std::string::npos) << text;
  const auto bad = testing::run({TACTILE_SLIP_TRAIN_PATH, "--controller", "paper"});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--controller"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace tactile::rig::train
