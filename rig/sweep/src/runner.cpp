// Running a sweep: one child rig process per scenario, J at a time (docs/slip.md, "The sweep").
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <list>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <thread>

#include "tactile/control/config.hpp"
#include "tactile/rig/sweep.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/process.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/util/text.hpp"

namespace tactile::rig::sweep {
namespace {

namespace fs = std::filesystem;

std::string duration_text(double s) {
  const auto whole = static_cast<long long>(s + 0.5);
  return fmt::format("{}:{:02d}:{:02d}", whole / 3600, static_cast<int>(whole / 60 % 60),
                     static_cast<int>(whole % 60));
}

// The last non-empty line of a file ("" when none or unreadable).
std::string last_line(const fs::path& path) {
  std::string text;
  try {
    text = util::read_file(path);
  } catch (const std::exception&) {
    return {};
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r'))
    text.pop_back();
  const auto nl = text.rfind('\n');
  return util::one_line(nl == std::string::npos ? text : text.substr(nl + 1));
}

struct Paths {
  fs::path scenario;
  fs::path report;
  fs::path log;
};

// Scenario NNNNN's file, and its run with `detector`'s report and log (NNNNN-DETECTOR).
Paths paths_of(const fs::path& out, std::uint64_t index, std::uint64_t scenarios,
               const std::string& detector) {
  const int width = std::max<int>(5, static_cast<int>(fmt::format("{}", scenarios).size()));
  const std::string name = fmt::format("{:0{}}", index, width);
  const std::string run = name + "-" + detector;
  return {out / "scenarios" / (name + ".yaml"), out / "reports" / (run + ".json"),
          out / "logs" / (run + ".log")};
}

struct Job {
  std::uint64_t index = 0;
  std::string detector;
};

// Whether a report was run with `grip` (--grip; empty: the drawn scenario's, which names none:
// the control core's default).
bool same_grip(const std::string& report_json, const std::string& grip) {
  const std::string want = grip.empty() ? control::to_string(control::Config{}.grip) : grip;
  const nlohmann::json r = nlohmann::json::parse(report_json);
  const auto c = r.find("controller");
  return c != r.end() && c->is_object() && c->value("grip", std::string()) == want;
}

// Starts PROGRAM --lockstep --scenario FILE --report FILE --slip-detector NAME [--grip G] in its
// own process group (a Ctrl-C at the terminal reaches the sweep alone, which stops its children),
// stdout to /dev/null, stderr to the scenario's log. Throws when it cannot start.
util::Process spawn_child(const std::string& program, const Paths& p, const std::string& detector,
                          const std::string& grip) {
  util::ProcessOptions o;
  o.argv = {program,    "--lockstep",      "--scenario",      p.scenario.string(),
            "--report", p.report.string(), "--slip-detector", detector};
  if (!grip.empty()) o.argv.insert(o.argv.end(), {"--grip", grip});
  o.stdout_to = util::Redirect::null();
  o.stderr_to = util::Redirect::file(p.log);
  o.own_process_group = true;
  o.die_with_parent = false;  // as before util::Process: a sweep's runs finish their reports
  return util::Process(std::move(o));
}

struct Running {
  Job job;
  util::Process process;
};

void write_outputs(const std::vector<Row>& rows, const SweepInfo& info, const fs::path& out) {
  util::write_file_atomic(out / "sweep.json", info_json(info));
  util::write_file_atomic(out / "sweep.csv", csv_text(rows));
  const std::string summary = summary_markdown(rows, info);
  util::write_file_atomic(out / "summary.md", summary);
  write_plot(rows, info, out / "sweep.png");
  std::fputs(summary.c_str(), stdout);
  std::fflush(stdout);
  util::log_info("wrote {}, {}, {} and {}", (out / "sweep.csv").string(),
                 (out / "summary.md").string(), (out / "sweep.png").string(),
                 (out / "sweep.json").string());
}

}  // namespace

std::vector<std::uint64_t> shard_indices(std::uint64_t scenarios, int shard, int shards) {
  if (shards < 1 || shard < 1 || shard > shards) {
    throw std::invalid_argument(fmt::format("shard {}/{}: K must be within 1..N", shard, shards));
  }
  std::vector<std::uint64_t> v;
  for (std::uint64_t i = static_cast<std::uint64_t>(shard - 1); i < scenarios;
       i += static_cast<std::uint64_t>(shards))
    v.push_back(i);
  return v;
}

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  Shard k;
  try {
    std::size_t used = 0;
    k.shard = std::stoi(text.substr(0, slash), &used);
    if (slash == std::string::npos || used != slash) throw std::invalid_argument(text);
    k.shards = std::stoi(text.substr(slash + 1), &used);
    if (used != text.size() - slash - 1) throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw std::invalid_argument("must be K/N, for example 2/3; got '" + text + "'");
  }
  if (k.shards < 1 || k.shard < 1 || k.shard > k.shards)
    throw std::invalid_argument("K/N needs 1 <= K <= N; got '" + text + "'");
  return k;
}

std::size_t run_sweep(const SweepOptions& o) {
  const std::vector<std::uint64_t> indices = shard_indices(o.scenarios, o.shard, o.shards);
  const std::string program = o.child_program.empty() ? "/proc/self/exe" : o.child_program;
  const int jobs =
      o.jobs > 0 ? o.jobs : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  for (const char* sub : {"scenarios", "reports", "logs"})
    util::check_writable_dir(o.out / sub);

  // A sweep.json is what says a run ended (sweep-slurm's test of a shard): none until this one has.
  std::error_code no_info;
  fs::remove(o.out / "sweep.json", no_info);
  // Every scenario file first: each can be re-run alone, also those a stop leaves unrun.
  std::map<std::uint64_t, Draw> draws;
  std::vector<Job> queue;
  std::vector<Row> rows;
  std::size_t kept = 0;
  for (const std::uint64_t i : indices) {
    draws[i] = draw_scenario(o.seed, i);
    draws[i].sensor = o.sensor;
    draws[i].lab_sensor = o.lab_sensor;
    const std::string yaml = scenario_yaml(draws[i], o.max_sim_time_s);
    const fs::path scenario = paths_of(o.out, i, o.scenarios, "").scenario;
    // --resume keeps a report only beside this draw's scenario file: not one of another sweep.
    bool same_scenario = false;
    if (o.resume && fs::exists(scenario)) same_scenario = util::read_file(scenario) == yaml;
    util::write_file_atomic(scenario, yaml);
    for (const std::string& detector : o.detectors) {
      const fs::path report = paths_of(o.out, i, o.scenarios, detector).report;
      if (same_scenario && fs::exists(report)) {
        try {
          // Reports are written whole (atomically): one that is there is the run's, unless it
          // was run with another grip (--grip: the scenario file is the same).
          const std::string text = util::read_file(report);
          if (!same_grip(text, o.grip)) throw std::runtime_error("run with another grip");
          for (Row& r : rows_from_report(draws[i], text))
            rows.push_back(std::move(r));
          ++kept;
          continue;
        } catch (const std::exception& e) {
          util::log_warn("sweep: {}: {}; running it again", report.string(), e.what());
        }
      }
      std::error_code ec;
      // A report left by an earlier sweep is not this run's.
      fs::remove(report, ec);
      queue.push_back({i, detector});
    }
  }
  if (o.resume) {
    util::log_info("sweep: resuming: {} runs kept from their reports, {} to run", kept,
                   queue.size());
  }

  util::log_info(
      "sweep: {} scenarios (shard {}/{} of {} drawn with seed {}), each with {}: {} runs, {} at "
      "a time",
      indices.size(), o.shard, o.shards, o.scenarios, o.seed, fmt::join(o.detectors, " and "),
      queue.size(), jobs);
  const auto start = std::chrono::steady_clock::now();
  std::list<Running> running;
  std::size_t next = 0;
  std::size_t done = 0;
  bool stopped = false;
  while ((!stopped && next < queue.size()) || !running.empty()) {
    if (util::stop_requested() && !stopped) {
      stopped = true;
      util::log_warn("sweep: stopping {} running scenarios", running.size());
      for (Running& r : running)
        r.process.signal(SIGTERM);
    }
    while (!stopped && next < queue.size() && static_cast<int>(running.size()) < jobs) {
      const Job job = queue[next++];
      const std::uint64_t i = job.index;
      try {
        running.push_back({job, spawn_child(program, paths_of(o.out, i, o.scenarios, job.detector),
                                            job.detector, o.grip)});
      } catch (const std::exception& e) {
        // 127: the shell's "cannot run"
        rows.push_back(failed_row(draws[i], job.detector, 127, e.what()));
        util::log_warn("sweep: scenario {}: {}", i, e.what());
        ++done;
      }
    }
    const auto ended = std::find_if(running.begin(), running.end(),
                                    [](Running& r) { return !r.process.running(); });
    if (ended == running.end()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const Job job = ended->job;
    const int code = ended->process.exit_status().value_or(-1);
    const std::uint64_t i = job.index;
    running.erase(ended);
    if (stopped) continue;  // cut short by the stop: not a result
    const Paths p = paths_of(o.out, i, o.scenarios, job.detector);
    if (code == 0) {
      try {
        for (Row& r : rows_from_report(draws[i], util::read_file(p.report)))
          rows.push_back(std::move(r));
      } catch (const std::exception& e) {
        rows.push_back(failed_row(draws[i], job.detector, 0,
                                  util::one_line(std::string("bad report: ") + e.what())));
      }
    } else {
      rows.push_back(failed_row(draws[i], job.detector, code, last_line(p.log)));
      util::log_warn("sweep: scenario {} ({}) failed with status {}: {}", i, job.detector, code,
                     last_line(p.log));
    }
    ++done;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double remaining =
        elapsed / static_cast<double>(done) * static_cast<double>(queue.size() - done);
    util::log_info("sweep: {}/{} runs done, {} elapsed, about {} remaining", done, queue.size(),
                   duration_text(elapsed), duration_text(remaining));
  }
  SweepInfo info{o.seed,           o.scenarios,
                 o.max_sim_time_s, o.lab_sensor ? o.lab_sensor->calibration : std::string(),
                 o.shard,          o.shards,
                 stopped};
  if (stopped) util::log_warn("sweep: stopped; {} of {} runs done", done, queue.size());
  write_outputs(rows, info, o.out);
  return rows.size();
}

std::size_t merge_sweeps(const std::vector<fs::path>& dirs, const fs::path& out) {
  if (dirs.empty()) throw std::invalid_argument("nothing to merge");
  std::vector<Row> rows;
  std::map<std::string, fs::path> seen;  // "index method" -> directory
  SweepInfo merged;
  for (std::size_t d = 0; d < dirs.size(); ++d) {
    const fs::path info_path = dirs[d] / "sweep.json";
    const SweepInfo info = parse_info(util::read_file(info_path), info_path.string());
    if (d == 0) {
      merged = info;
    } else if (info.seed != merged.seed || info.scenarios != merged.scenarios ||
               info.max_sim_time_s != merged.max_sim_time_s ||
               info.calibration != merged.calibration) {
      throw std::runtime_error(fmt::format(
          "{}: seed {}, {} scenarios, time limit {} s, calibration '{}'; {} has seed {}, {} "
          "scenarios, {} s, calibration '{}': not shards of one sweep",
          info_path.string(), info.seed, info.scenarios, info.max_sim_time_s, info.calibration,
          dirs[0].string(), merged.seed, merged.scenarios, merged.max_sim_time_s,
          merged.calibration));
    }
    merged.stopped = merged.stopped || info.stopped;
    const fs::path csv = dirs[d] / "sweep.csv";
    for (Row& r : parse_csv(util::read_file(csv), csv.string())) {
      const std::string key = r.at("index") + " " + r.at("method");
      const auto [it, fresh] = seen.emplace(key, dirs[d]);
      if (!fresh) {
        throw std::runtime_error(fmt::format("{}: scenario {} (method {}) is in {} too",
                                             csv.string(), r.at("index"), r.at("method"),
                                             it->second.string()));
      }
      rows.push_back(std::move(r));
    }
  }
  merged.shard = 1;
  merged.shards = 1;
  std::set<std::string> indices;
  for (const Row& r : rows)
    indices.insert(r.at("index"));
  if (indices.size() < merged.scenarios) {
    util::log_warn("sweep-merge: {} of {} scenarios present", indices.size(), merged.scenarios);
  }
  util::check_writable_dir(out);
  write_outputs(rows, merged, out);
  return rows.size();
}

}  // namespace tactile::rig::sweep
