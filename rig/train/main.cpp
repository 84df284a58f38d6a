// slip_train: trains the learned slip detector's model (docs/slip.md, "The learned combiner").
// It draws the sweep's scenarios for each training seed, runs each in lockstep with the field
// detector in the controller, logs every measured element-frame's signals with the truth's label,
// fits gradient-boosted oblivious trees and writes the model as C++ source (slip_model.inc).
// Deterministic: the same seeds and options give the same file, whatever --jobs.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "tactile/cli/run.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/rig/boosted_trees.hpp"
#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/sweep.hpp"
#include "tactile/rig/training_rows.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/percentile.hpp"
#include "tactile/util/stop.hpp"

namespace {

namespace rig = tactile::rig;
namespace control = tactile::control;
using tactile::util::nearest_rank_percentile;

struct Run {
  std::uint64_t seed = 0;
  std::uint64_t index = 0;
  rig::SlipFeatureLog log;
  std::string error;
};

// --rows-out: the rows of the runs `selected` (a shard's), with what every shard shares.
rig::train::TrainingRows shard_rows(const std::vector<Run>& runs,
                                    const std::vector<std::uint64_t>& selected,
                                    rig::train::TrainingRows shared) {
  for (const std::uint64_t k : selected) {
    const Run& r = runs[k];
    rig::train::RowsOfRun out{r.seed, r.index, {}, r.log.label, r.log.weight};
    for (const auto& row : r.log.x)
      out.x.insert(out.x.end(), row.begin(), row.end());
    shared.runs.push_back(std::move(out));
  }
  return shared;
}

// --rows-in: the shards' files into `runs` (planned from the files' seeds and scenarios), each
// run once; throws naming the file for shards of different trainings, a run twice or missing.
void load_rows(const std::vector<std::string>& files, rig::train::TrainingRows& shared,
               std::vector<Run>& runs) {
  std::vector<std::string> from;  // per run, the file it came from
  for (std::size_t f = 0; f < files.size(); ++f) {
    rig::train::TrainingRows part =
        rig::train::parse_rows_file(tactile::util::read_file(files[f]), files[f]);
    if (!rig::sweep::sensor_set_from_string(part.sensor)) {
      throw std::runtime_error(fmt::format("{}: sensor '{}', not {}", files[f], part.sensor,
                                           rig::sweep::kSensorSetNames));
    }
    if (f == 0) {
      shared = part;
      for (const std::uint64_t s : shared.seeds)
        for (std::uint64_t i = 0; i < shared.scenarios; ++i)
          runs.push_back(Run{s, i, {}, {}});
      from.assign(runs.size(), "");
    } else if (part.seeds != shared.seeds || part.scenarios != shared.scenarios ||
               part.max_time_s != shared.max_time_s || part.controller != shared.controller ||
               part.grip != shared.grip || part.features != shared.features ||
               part.shards != shared.shards || part.calibration != shared.calibration ||
               part.sensor != shared.sensor) {
      throw std::runtime_error(fmt::format(
          "{}: seeds {}, {} scenarios, max time {}, controller {}, grip {}, calibration '{}', "
          "sensor {}, {} shards; {} has seeds {}, {}, {}, {}, {}, '{}', {}, {}: not shards of one "
          "training",
          files[f], fmt::join(part.seeds, ","), part.scenarios, part.max_time_s, part.controller,
          part.grip, part.calibration, part.sensor, part.shards, files[0],
          fmt::join(shared.seeds, ","), shared.scenarios, shared.max_time_s, shared.controller,
          shared.grip, shared.calibration, shared.sensor, shared.shards));
    }
    if (part.features != control::kSlipFeatures) {
      throw std::runtime_error(fmt::format("{}: rows of {} features; this slip_train has {}",
                                           files[f], part.features, control::kSlipFeatures));
    }
    for (rig::train::RowsOfRun& r : part.runs) {
      const auto seed = std::find(shared.seeds.begin(), shared.seeds.end(), r.seed);
      if (seed == shared.seeds.end() || r.index >= shared.scenarios)
        throw std::runtime_error(fmt::format("{}: seed {} scenario {} is not one of its runs",
                                             files[f], r.seed, r.index));
      const auto k =
          static_cast<std::size_t>(seed - shared.seeds.begin()) * shared.scenarios + r.index;
      if (!from[k].empty())
        throw std::runtime_error(fmt::format("{}: seed {} scenario {} is in {} too", files[f],
                                             r.seed, r.index, from[k]));
      from[k] = files[f];
      rig::SlipFeatureLog& log = runs[k].log;
      for (std::size_t n = 0; n < r.label.size(); ++n) {
        control::SlipFeatures row{};
        std::copy_n(r.x.begin() + static_cast<std::ptrdiff_t>(n * part.features), part.features,
                    row.begin());
        log.x.push_back(row);
      }
      log.label = std::move(r.label);
      log.weight = std::move(r.weight);
    }
  }
  const auto missing = std::find(from.begin(), from.end(), "");
  if (missing != from.end()) {
    const Run& r = runs[static_cast<std::size_t>(missing - from.begin())];
    throw std::runtime_error(fmt::format(
        "{} of {} runs missing, the first seed {} scenario {}: a shard's rows are not among "
        "--rows-in",
        std::count(from.begin(), from.end(), ""), runs.size(), r.seed, r.index));
  }
}

// Per run, weighted counts at each decision level: precision and recall of the rows.
struct Tally {
  std::vector<double> tp, fp, fn;
};

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("slip_train");
  // The defaults make the model in the repository.
  std::vector<std::uint64_t> seeds{101, 102, 103, 104};
  std::uint64_t scenarios = 80;
  unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
  std::string out = "common/control/src/slip_model.inc";
  double max_time_s = 0;
  std::optional<double> decision_level;
  std::string controller = "field";
  std::string grip = "paper";
  rig::train::BoostParams params;
  params.trees = 64;
  params.depth = 7;
  params.learning_rate = 0.25;
  std::string log_level = "info";
  CLI::App app{
      "slip_train: trains the learned slip detector (docs/slip.md, \"The learned combiner\").\n"
      "Runs scenarios 0..N-1 of the sweep's draw for each seed in lockstep (the field detector\n"
      "in the controller), logs each measured element-frame's signals with the truth's label,\n"
      "fits boosted oblivious trees and writes the model as C++ source to --out, which\n"
      "common/control/src/slip_detector.cpp includes; rebuild to use it. Never train on the\n"
      "seeds the benchmark sweep is scored on. On a cluster: --shard K/N --rows-out FILE runs a\n"
      "share of the runs and writes their rows, --rows-in FILE... fits once from all shards'\n"
      "rows (scripts/sweep-slurm train). For a lab's own sensor: --calibration FILE; for a\n"
      "sensor drawn per scenario (a model that survives another sensor): --sensor drawn."};
  app.add_option("--seeds", seeds, "training sweep seeds, separated by commas")
      ->delimiter(',')
      ->check(CLI::Validator(
          [](const std::string& seed) {
            // Each item; CLI11 would read "" as 0.
            return !seed.empty() && seed.find_first_not_of("0123456789") == std::string::npos
                       ? std::string()
                       : "whole numbers separated by commas; got '" + seed + "'";
          },
          ""))
      ->default_str("101,102,103,104");
  app.add_option("--scenarios", scenarios, "scenarios per seed")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{100000}))
      ->capture_default_str();
  app.add_option("--jobs", jobs, "runs at once (threads)")
      ->check(CLI::Range(1u, 64u))
      ->capture_default_str();
  app.add_option("--out", out, "the model's source file")->capture_default_str();
  app.add_option("--max-time", max_time_s, "cap each run's simulated time (s; 0: the scenario's)")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--trees", params.trees, "boosting rounds")
      ->check(CLI::Range(std::size_t{1}, std::size_t{4096}))
      ->capture_default_str();
  app.add_option("--depth", params.depth, "depth of each oblivious tree")
      ->check(CLI::Range(std::size_t{1}, std::size_t{8}))
      ->capture_default_str();
  app.add_option("--learning-rate", params.learning_rate, "shrinkage of each tree")
      ->check(CLI::Range(1e-4, 1.0))
      ->capture_default_str();
  app.add_option("--decision", decision_level,
                 "the decision level, instead of the one the training rows choose (docs/slip.md: "
                 "chosen on a validation sweep)")
      ->check(CLI::Range(-2.0, 2.0));
  app.add_option("--controller", controller,
                 "the slip detector in the controller of the training runs: field (the rules), or "
                 "learned (the model compiled into this slip_train: its own decisions steer the "
                 "runs it is trained on, as they steer the sweep's)")
      ->check(CLI::IsMember({"field", "learned"}))
      ->capture_default_str();
  app.add_option("--grip", grip,
                 "the grip of the training runs: paper (the paper's F1 and re-compression), "
                 "margin (docs/control.md, \"The margin grip\"), or mixed (each seed's odd "
                 "scenarios under the margin grip, the even under the paper's)")
      ->check(CLI::IsMember({"paper", "margin", "mixed"}))
      ->capture_default_str();
  std::string calibration;
  app.add_option("--calibration", calibration,
                 "a lab's calibration file (tactile-calibration/1): every training run's rig "
                 "renders that sensor, its layout, curves, thresholds and image (docs/slip.md, "
                 "\"Retraining for your own sensor\")");
  std::string sensor = "rig";
  app.add_option("--sensor", sensor,
                 "the sensor of the training runs, as rig --sweep --sensor: rig (the rig's "
                 "Gaussian spot), feelers (the paper's feeler element) or drawn (one drawn per "
                 "scenario) (docs/slip.md, \"The drawn sensor\")")
      ->check(CLI::Validator(
          [](const std::string& name) {
            return rig::sweep::sensor_set_from_string(name)
                       ? std::string()
                       : "must be " + std::string(rig::sweep::kSensorSetNames) + "; got '" + name +
                             "'";
          },
          "SET"))
      ->capture_default_str();
  std::string shard;
  std::string rows_out;
  std::vector<std::string> rows_in;
  app.add_option("--shard", shard,
                 "run only part K of N of the runs (runs k, in seed-then-scenario order, with "
                 "k mod N = K - 1), as K/N; with --rows-out (docs/slip.md, \"Training on a "
                 "cluster\")");
  auto* rows_out_opt = app.add_option("--rows-out", rows_out,
                                      "write the runs' training rows to this file and fit nothing");
  auto* rows_in_opt =
      app.add_option("--rows-in", rows_in,
                     "fit from these rows files (every shard's --rows-out) instead of running; "
                     "the seeds, scenarios, max time, controller and grip are theirs")
          ->excludes(rows_out_opt);
  tactile::cli::add_log_level(app, log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    tactile::util::set_log_level(tactile::util::parse_log_level(log_level));
    tactile::util::install_stop_handlers();

    rig::train::TrainingRows shared;
    shared.seeds = seeds;
    shared.scenarios = scenarios;
    shared.max_time_s = max_time_s;
    shared.controller = controller;
    shared.grip = grip;
    shared.sensor = sensor;
    shared.features = control::kSlipFeatures;
    // Refused now, naming the file, not in every run; the runs and the rows name it absolute.
    std::optional<rig::LabSensor> lab_sensor;
    if (!calibration.empty() && !*rows_in_opt) {
      lab_sensor = rig::load_lab_sensor(calibration);
      shared.calibration = lab_sensor->calibration;
      calibration = shared.calibration;
    }
    if (!shard.empty()) {
      if (!*rows_out_opt) throw tactile::cli::UsageError("--shard needs --rows-out");
      try {
        const rig::sweep::Shard k = rig::sweep::parse_shard(shard);
        shared.shard = k.shard;
        shared.shards = k.shards;
      } catch (const std::invalid_argument& e) {
        throw tactile::cli::UsageError(std::string("--shard: ") + e.what());
      }
    }
    std::vector<Run> runs;
    std::vector<std::uint64_t> selected;
    if (*rows_in_opt) {
      for (const char* name : {"--seeds", "--scenarios", "--max-time", "--controller", "--grip",
                               "--calibration", "--sensor"}) {
        if (app.count(name) > 0)
          throw tactile::cli::UsageError(std::string("--rows-in takes no ") + name +
                                         ": the rows files say how they were made");
      }
      load_rows(rows_in, shared, runs);
      seeds = shared.seeds;
      scenarios = shared.scenarios;
      max_time_s = shared.max_time_s;
      controller = shared.controller;
      grip = shared.grip;
      calibration = shared.calibration;
      sensor = shared.sensor;
    } else {
      for (const std::uint64_t s : seeds)
        for (std::uint64_t i = 0; i < scenarios; ++i)
          runs.push_back(Run{s, i, {}, {}});
      selected = rig::sweep::shard_indices(runs.size(), shared.shard, shared.shards);
    }
    std::atomic<std::size_t> next{0}, done{0};
    std::mutex print;
    const auto worker = [&] {
      for (std::size_t n; (n = next++) < selected.size();) {
        if (tactile::util::stop_requested()) return;
        Run& r = runs[selected[n]];
        try {
          rig::sweep::Draw d = rig::sweep::draw_scenario(r.seed, r.index);
          d.lab_sensor = lab_sensor;
          d.sensor = *rig::sweep::sensor_set_from_string(sensor);
          rig::Scenario sc =
              rig::parse_scenario(rig::sweep::scenario_yaml(d, max_time_s),
                                  fmt::format("seed {} scenario {}", r.seed, r.index));
          sc.slip_detector = controller;
          sc.grip = grip == "mixed" ? (r.index % 2 == 1 ? "margin" : "paper") : grip;
          rig::LockstepOptions opt;
          opt.record_series = false;
          opt.slip_features = &r.log;
          (void)rig::run_lockstep(sc, opt);
        } catch (const std::exception& e) {
          r.error = e.what();
        }
        const std::lock_guard lock(print);
        std::fprintf(stderr, "slip_train: run %zu/%zu (seed %llu scenario %llu): %zu rows\n",
                     ++done, selected.size(), static_cast<unsigned long long>(r.seed),
                     static_cast<unsigned long long>(r.index), r.log.label.size());
      }
    };
    std::vector<std::thread> threads;
    for (unsigned j = 0; j < jobs; ++j)
      threads.emplace_back(worker);
    for (auto& t : threads)
      t.join();
    if (tactile::util::stop_requested()) {
      std::fprintf(stderr, "slip_train: stopped before training: nothing written\n");
      return tactile::util::interrupted_exit_status();
    }
    for (const Run& r : runs) {
      if (!r.error.empty())
        throw std::runtime_error(fmt::format("seed {} scenario {}: {}", r.seed, r.index, r.error));
    }
    if (*rows_out_opt) {
      tactile::util::write_file_atomic(rows_out,
                                       rig::train::rows_file(shard_rows(runs, selected, shared)));
      std::fprintf(stderr, "slip_train: wrote the rows of %zu runs (shard %d/%d) to %s\n",
                   selected.size(), shared.shard, shared.shards, rows_out.c_str());
      return 0;
    }

    // The rows in run order, so the model does not depend on --jobs.
    std::vector<float> x;
    std::vector<std::uint8_t> label;
    std::vector<float> weight;
    for (const Run& r : runs) {
      for (const auto& row : r.log.x)
        x.insert(x.end(), row.begin(), row.end());
      label.insert(label.end(), r.log.label.begin(), r.log.label.end());
      weight.insert(weight.end(), r.log.weight.begin(), r.log.weight.end());
    }
    std::size_t positives = 0;
    for (const auto l : label)
      positives += l;
    // The fit's weights: each run weighs as much as the mean run (within a factor of 8), since
    // the sweep scores each run's precision and recall, not the pooled rows: a 60 fps run logs a
    // sixth of a 400 fps run's rows and would otherwise hardly move the fit.
    std::vector<std::size_t> run_rows;
    for (const Run& r : runs)
      run_rows.push_back(r.log.label.size());
    const std::vector<float> fit_weight = rig::train::balance_runs(weight, run_rows, 8.0);
    std::fprintf(stderr, "slip_train: %zu rows (%zu slipping), %zu features; fitting %zu trees\n",
                 label.size(), positives, control::kSlipFeatures, params.trees);
    const control::ObliviousForest model = rig::train::fit_boosted_trees(
        x, control::kSlipFeatures, label, fit_weight, params, [&](std::size_t t) {
          if (t % 8 == 0 || t == params.trees)
            std::fprintf(stderr, "slip_train: tree %zu/%zu\n", t, params.trees);
        });

    // The decision level: the one of a grid that maximises the median plus the 5th percentile of
    // the runs' F1 on their own rows (precision and recall per run, as the sweep scores them).
    std::vector<double> levels;
    for (int k = -20; k <= 20; ++k)
      levels.push_back(0.1 * k);
    std::vector<Tally> tallies(runs.size());
    std::size_t row = 0;
    for (std::size_t k = 0; k < runs.size(); ++k) {
      Tally& t = tallies[k];
      t.tp.assign(levels.size(), 0.0);
      t.fp.assign(levels.size(), 0.0);
      t.fn.assign(levels.size(), 0.0);
      for (std::size_t n = 0; n < runs[k].log.label.size(); ++n, ++row) {
        // The controller's own score and comparison: in float (SlipDetector::decide_learned).
        const float s = model.score({&x[row * control::kSlipFeatures], control::kSlipFeatures});
        const bool y = label[row] != 0;
        const auto w = static_cast<double>(weight[row]);
        for (std::size_t l = 0; l < levels.size(); ++l) {
          const bool p = s > static_cast<float>(levels[l]);
          if (p && y) t.tp[l] += w;
          if (p && !y) t.fp[l] += w;
          if (!p && y) t.fn[l] += w;
        }
      }
    }
    double best = -1, decision = 0;
    std::string table;
    for (std::size_t l = 0; l < levels.size(); ++l) {
      std::vector<double> p, r, f1;
      for (const Tally& t : tallies) {
        if (t.tp[l] + t.fn[l] <= 0) continue;
        const double pr = t.tp[l] + t.fp[l] > 0 ? t.tp[l] / (t.tp[l] + t.fp[l]) : 1.0;
        const double re = t.tp[l] / (t.tp[l] + t.fn[l]);
        p.push_back(pr);
        r.push_back(re);
        f1.push_back(pr + re > 0 ? 2 * pr * re / (pr + re) : 0.0);
      }
      const double value = nearest_rank_percentile(f1, 0.5) + nearest_rank_percentile(f1, 0.05);
      std::fprintf(stderr,
                   "slip_train: decision %+.1f: precision %.3f / %.3f, recall %.3f / %.3f "
                   "(median / 5th percentile over runs)\n",
                   levels[l], nearest_rank_percentile(p, 0.5), nearest_rank_percentile(p, 0.05),
                   nearest_rank_percentile(r, 0.5), nearest_rank_percentile(r, 0.05));
      if (value > best) {
        best = value;
        decision = levels[l];
      }
    }
    if (decision_level) {
      std::fprintf(stderr, "slip_train: decision %+.1f chosen on the training rows; %+.2f asked\n",
                   decision, *decision_level);
      decision = *decision_level;
    }
    const std::string training = fmt::format(
        "slip_train --seeds {} --scenarios {} --trees {} --depth {} --learning-rate "
        "{}{}{}{}{}{}{}: "
        "{} rows, decision {:.2f}",
        fmt::join(seeds, ","), scenarios, params.trees, params.depth, params.learning_rate,
        controller != "field" ? fmt::format(" --controller {}", controller) : std::string(),
        grip != "paper" ? fmt::format(" --grip {}", grip) : std::string(),
        max_time_s > 0 ? fmt::format(" --max-time {}", max_time_s) : std::string(),
        decision_level ? fmt::format(" --decision {}", *decision_level) : std::string(),
        calibration.empty() ? std::string() : fmt::format(" --calibration {}", calibration),
        sensor != "rig" ? fmt::format(" --sensor {}", sensor) : std::string(), label.size(),
        decision);
    tactile::util::write_file_atomic(out, rig::train::model_source(model, decision, training));
    std::fprintf(stderr, "slip_train: wrote %s (%s)\n", out.c_str(), training.c_str());
    return 0;
  });
}
