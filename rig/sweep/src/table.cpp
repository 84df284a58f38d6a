// The sweep's table: rows from the runs' reports, the CSV, sweep.json and the summary.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/sweep.hpp"

namespace tactile::rig::sweep {
namespace {

using nlohmann::json;

std::size_t column_index(const std::string& name) {
  const auto& c = columns();
  const auto it = std::find(c.begin(), c.end(), name);
  if (it == c.end()) throw std::logic_error("sweep: no column '" + name + "'");
  return static_cast<std::size_t>(it - c.begin());
}

Row drawn_row(const Draw& d, const std::string& method) {
  Row row;
  row.cells.assign(columns().size(), std::string());
  const auto set = [&](const char* column, std::string value) {
    row.cells[column_index(column)] = std::move(value);
  };
  set("index", fmt::format("{}", d.index));
  set("method", method);
  set("case", to_string(d.scenario_case));
  set("scenario_seed", fmt::format("{}", d.scenario_seed));
  set("mass_kg", fmt::format("{}", d.mass_kg));
  set("radius_mm", fmt::format("{}", d.radius_mm));
  set("friction", fmt::format("{}", d.friction));
  set("kinetic_ratio", fmt::format("{}", d.kinetic_ratio));
  set("free_turn_deg", fmt::format("{}", d.free_turn_deg));
  set("vibration_mm", fmt::format("{}", d.vibration_mm));
  set("vibration_hz", fmt::format("{}", d.vibration_hz));
  set("noise_sigma", fmt::format("{}", d.noise_sigma));
  set("fps", fmt::format("{}", d.fps));
  set("bit_depth", fmt::format("{}", d.bit_depth));
  const bool drawn = d.sensor == SensorSet::kDrawn;
  const DrawnSensor& ds = d.drawn_sensor;
  const bool feelers = d.sensor == SensorSet::kFeelers || (drawn && ds.feelers);
  set("element_model", feelers ? "feelers" : "gaussian");
  if (drawn) {
    set("normal_stiffness_n_per_mm", fmt::format("{}", ds.normal_stiffness_n_per_mm));
    set("spot_scale", fmt::format("{}", ds.spot_scale));
    set("shot_noise_gain", fmt::format("{}", ds.shot_noise_gain));
    set("normal_curve_error", fmt::format("{}", ds.normal_curve_error));
    set("shear_curve_error", fmt::format("{}", ds.shear_curve_error));
    set("layout_offset_x_px", fmt::format("{}", ds.layout_offset_x_px));
    set("layout_offset_y_px", fmt::format("{}", ds.layout_offset_y_px));
  }
  set("disturbance", to_string(d.disturbance));
  if (d.crush_force_n > 0) set("crush_force_N", fmt::format("{}", d.crush_force_n));
  return row;
}

// A JSON value as a cell: numbers in their shortest exact text, null as empty.
std::string cell(const json& v) {
  if (v.is_null()) return {};
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return fmt::format("{}", v.get<std::int64_t>());
  if (v.is_number()) return fmt::format("{}", v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  throw std::runtime_error("unexpected value " + v.dump());
}

const json& need(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key)) throw std::runtime_error(std::string("no key ") + key);
  return j.at(key);
}

// RFC 4180: a field with a comma, quote or line break is quoted, its quotes doubled.
std::string quoted(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) {
    if (c == '"') q += '"';
    q += c == '\n' || c == '\r' ? ' ' : c;
  }
  return q + "\"";
}

double percentile(const std::vector<double>& v, double q) {
  return nearest_rank_percentile(v, q);
}

std::string number_text(double v) {
  return std::isfinite(v) ? fmt::format("{:.4g}", v) : std::string("-");
}

// The classifications per case (docs/slip.md, "Negative cases"): the target is a grasp and a
// release in every normal scenario and no classification in a negative one; the negative
// scenarios that failed are listed by index.
std::string case_table(const std::vector<const Row*>& rows) {
  std::string out =
      "\n| case | scenarios | grasp on the lift | release at the bottle | opened in the air | "
      "negative case passed |\n|---|---|---|---|---|---|\n";
  std::string failed;
  for (const Case c : {Case::kNormal, Case::kBottleDisplaced, Case::kCapHeld}) {
    const std::string name = to_string(c);
    std::size_t n = 0, grasp = 0, release = 0, opened = 0, passed = 0;
    std::vector<std::string> failing;
    for (const Row* r : rows) {
      if (r->at("case") != name) continue;
      ++n;
      grasp += r->at("grasp_classified") == "grasp" ? 1 : 0;
      release += r->at("release_classified") == "release" ? 1 : 0;
      opened += r->at("opened_in_air") == "true" ? 1 : 0;
      passed += r->at("negative_case_passed") == "true" ? 1 : 0;
      if (c != Case::kNormal && r->at("negative_case_passed") != "true")
        failing.push_back(r->at("index"));
    }
    out += fmt::format("| {} | {} | {} | {} | {} | {} |\n", name, n, grasp, release, opened,
                       c == Case::kNormal ? std::string("-") : fmt::format("{} of {}", passed, n));
    if (!failing.empty())
      failed += fmt::format("\n{} failed (index): {}\n", name, fmt::join(failing, ", "));
  }
  return out + failed;
}

// Completion, drops and OVER of the normal scenarios apart for those the hand can hold within F2
// and those it cannot (docs/slip.md, "Holdable within F2"); the latter listed by index.
std::string hold_table(const std::vector<const Row*>& rows) {
  std::string out =
      "\n| normal scenarios | scenarios | completed | dropped | OVER raised "
      "|\n|---|---|---|---|---|\n";
  std::vector<std::string> not_holdable;
  for (const bool holdable : {true, false}) {
    std::size_t n = 0, completed = 0, dropped = 0, over = 0;
    for (const Row* r : rows) {
      if (r->at("holdable") == (holdable ? "true" : "false")) {
        if (!holdable) not_holdable.push_back(r->at("index"));
        if (r->at("case") != "normal") continue;
        ++n;
        completed += r->at("completed") == "true" ? 1 : 0;
        dropped += r->at("dropped") == "true" ? 1 : 0;
        over += r->number("over_events") > 0 ? 1 : 0;
      }
    }
    out += fmt::format("| {} | {} | {} | {} | {} |\n",
                       holdable ? "holdable within F2" : "not holdable within F2", n, completed,
                       dropped, over);
  }
  out += fmt::format("\nNot holdable within F2 (index, any case): {}\n",
                     not_holdable.empty() ? std::string("none")
                                          : fmt::format("{}", fmt::join(not_holdable, ", ")));
  return out;
}

// The outcomes per disturbance drawn (docs/slip.md, "Disturbances and fragile objects"), and of
// the fragile objects: how many the grip broke.
std::string disturbance_table(const std::vector<const Row*>& rows) {
  std::string out =
      "\n| disturbance | scenarios | completed | dropped | OVER raised | fragile | broken "
      "|\n|---|---|---|---|---|---|---|\n";
  for (const Disturbance d : {Disturbance::kNone, Disturbance::kPullStep, Disturbance::kPullRamp,
                              Disturbance::kMassStep, Disturbance::kKnock}) {
    const std::string name = to_string(d);
    std::size_t n = 0, completed = 0, dropped = 0, over = 0, fragile = 0, broken = 0;
    for (const Row* r : rows) {
      if (r->at("disturbance") != name) continue;
      ++n;
      completed += r->at("completed") == "true" ? 1 : 0;
      dropped += r->at("dropped") == "true" ? 1 : 0;
      over += r->number("over_events") > 0 ? 1 : 0;
      fragile += r->at("crush_force_N").empty() ? 0 : 1;
      broken += r->at("broken") == "true" ? 1 : 0;
    }
    out += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", name, n, completed, dropped, over,
                       fragile, broken);
  }
  return out;
}

}  // namespace

const std::vector<std::string>& columns() {
  static const std::vector<std::string> c{"index",
                                          "method",
                                          "case",
                                          "scenario_seed",
                                          "mass_kg",
                                          "radius_mm",
                                          "friction",
                                          "kinetic_ratio",
                                          "free_turn_deg",
                                          "vibration_mm",
                                          "vibration_hz",
                                          "noise_sigma",
                                          "fps",
                                          "bit_depth",
                                          "element_model",
                                          "normal_stiffness_n_per_mm",
                                          "spot_scale",
                                          "shot_noise_gain",
                                          "normal_curve_error",
                                          "shear_curve_error",
                                          "layout_offset_x_px",
                                          "layout_offset_y_px",
                                          "exit_status",
                                          "completed",
                                          "end_reason",
                                          "dropped",
                                          "over_events",
                                          "grasp_classified",
                                          "release_classified",
                                          "negative_case_passed",
                                          "opened_in_air",
                                          "holdable",
                                          "grip_needed_N",
                                          "grip_allowed_N",
                                          "tightened_cycle",
                                          "true_tight_cycle",
                                          "tight_cycle_error",
                                          "tight_time_error_s",
                                          "tight_error_deg",
                                          "precision",
                                          "recall",
                                          "ideal_precision",
                                          "ideal_recall",
                                          "precision_without_edges",
                                          "recall_without_edges",
                                          "ideal_precision_without_edges",
                                          "ideal_recall_without_edges",
                                          "incipient_lead_frames",
                                          "incipient_episodes",
                                          "incipient_detected",
                                          "max_fz_N",
                                          "false_slips",
                                          "recompressions",
                                          "grip_ratio_p50",
                                          "grip_ratio_p95",
                                          "grip_instant_ratio_p50",
                                          "cap_slide_carry_mm",
                                          "disturbance",
                                          "crush_force_N",
                                          "broken",
                                          "peak_grip_over_crush",
                                          "sim_time_s",
                                          "error"};
  return c;
}

const std::string& Row::at(const std::string& column) const {
  return cells.at(column_index(column));
}

double Row::number(const std::string& column) const {
  const std::string& s = at(column);
  if (s.empty()) return std::numeric_limits<double>::quiet_NaN();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() ? v : std::numeric_limits<double>::quiet_NaN();
}

std::vector<Row> rows_from_report(const Draw& d, const std::string& report_json) {
  const json r = json::parse(report_json);
  const json& slip = need(r, "slip");
  Row row = drawn_row(
      d, slip.contains("detector") ? slip.at("detector").get<std::string>() : std::string("paper"));
  const auto set = [&](const char* column, std::string value) {
    row.cells[column_index(column)] = std::move(value);
  };
  set("exit_status", "0");
  set("completed", cell(need(r, "completed")));
  set("end_reason", cell(need(need(r, "lockstep"), "end_reason")));
  set("dropped", cell(need(r, "dropped")));
  set("over_events", cell(need(r, "over_events")));
  set("grasp_classified", cell(need(r, "grasp_classified")));
  set("release_classified", cell(need(r, "release_classified")));
  if (cell(need(r, "case")) != to_string(d.scenario_case)) {
    throw std::runtime_error("the report's case is " + need(r, "case").dump() + ", the draw's " +
                             to_string(d.scenario_case));
  }
  set("negative_case_passed", cell(need(r, "negative_case_passed")));
  set("opened_in_air", cell(need(r, "opened_in_air")));
  set("holdable", cell(need(r, "holdable")));
  set("grip_needed_N", cell(need(need(r, "hold"), "grip_needed_N")));
  set("grip_allowed_N", cell(need(need(r, "hold"), "grip_allowed_N")));
  const json& tightened = need(r, "tightened_cycle");
  const json& true_tight = need(r, "true_tight_cycle");
  set("tightened_cycle", cell(tightened));
  set("true_tight_cycle", cell(true_tight));
  if (tightened.is_number_integer() && true_tight.is_number_integer()) {
    set("tight_cycle_error",
        fmt::format("{}", tightened.get<std::int64_t>() - true_tight.get<std::int64_t>()));
  }
  // Seconds from the cap meeting its stop to "tight", and the wrist's turn between them.
  set("tight_time_error_s", cell(need(r, "tight_time_error_s")));
  set("tight_error_deg", cell(need(r, "tight_error_deg")));
  set("precision", cell(need(slip, "precision")));
  set("recall", cell(need(slip, "recall")));
  const json& ideal = need(slip, "ideal_sensor");
  set("ideal_precision", cell(need(ideal, "precision")));
  set("ideal_recall", cell(need(ideal, "recall")));
  if (slip.contains("without_edges")) {
    set("precision_without_edges", cell(need(slip.at("without_edges"), "precision")));
    set("recall_without_edges", cell(need(slip.at("without_edges"), "recall")));
  }
  if (ideal.contains("without_edges")) {
    set("ideal_precision_without_edges", cell(need(ideal.at("without_edges"), "precision")));
    set("ideal_recall_without_edges", cell(need(ideal.at("without_edges"), "recall")));
  }
  // Reports from before the incipient lead have none: empty cells.
  for (const char* key : {"incipient_lead_frames", "incipient_episodes", "incipient_detected"}) {
    if (slip.contains(key)) set(key, cell(slip.at(key)));
  }
  set("max_fz_N", cell(need(r, "max_fz_N")));
  set("false_slips", cell(need(slip, "false_positives")));
  set("recompressions", cell(need(r, "recompressions")));
  // Reports from before the grip's truth have none: empty cells.
  if (r.contains("grip")) {
    const json& grip = r.at("grip");
    set("grip_ratio_p50", cell(need(grip, "ratio_p50")));
    set("grip_ratio_p95", cell(need(grip, "ratio_p95")));
    set("grip_instant_ratio_p50", cell(need(grip, "instant_ratio_p50")));
    set("cap_slide_carry_mm", cell(need(grip, "cap_slide_carry_mm")));
  }
  // A fragile object's outcome; empty for one that is not.
  if (r.contains("fragile")) {
    set("broken", cell(need(r.at("fragile"), "broken")));
    set("peak_grip_over_crush", cell(need(r.at("fragile"), "peak_over_crush")));
  }
  set("sim_time_s", cell(need(need(r, "lockstep"), "sim_time_s")));
  return {row};
}

Row failed_row(const Draw& d, const std::string& method, int exit_status,
               const std::string& last_stderr_line) {
  Row row = drawn_row(d, method);
  row.cells[column_index("exit_status")] = fmt::format("{}", exit_status);
  row.cells[column_index("error")] = last_stderr_line;
  return row;
}

std::string csv_text(std::vector<Row> rows) {
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    const double ia = a.number("index");
    const double ib = b.number("index");
    return ia != ib ? ia < ib : a.at("method") < b.at("method");
  });
  std::string out;
  for (std::size_t i = 0; i < columns().size(); ++i)
    out += (i ? "," : "") + columns()[i];
  out += '\n';
  for (const Row& row : rows) {
    for (std::size_t i = 0; i < row.cells.size(); ++i)
      out += (i ? "," : "") + quoted(row.cells[i]);
    out += '\n';
  }
  return out;
}

std::vector<Row> parse_csv(const std::string& text, const std::string& source) {
  std::vector<std::vector<std::string>> records;
  std::vector<std::string> fields(1);
  bool in_quotes = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        in_quotes = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      in_quotes = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c == '\n') {
      records.push_back(std::move(fields));
      fields.assign(1, std::string());
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  if (fields.size() > 1 || !fields[0].empty()) records.push_back(std::move(fields));
  if (records.empty() || records[0] != columns()) {
    throw std::runtime_error(source + ": line 1: not a sweep CSV (the header must be '" +
                             fmt::format("{}", fmt::join(columns(), ",")) + "')");
  }
  std::vector<Row> rows;
  for (std::size_t r = 1; r < records.size(); ++r) {
    if (records[r].size() != columns().size()) {
      throw std::runtime_error(fmt::format("{}: line {}: {} fields, the header has {}", source,
                                           r + 1, records[r].size(), columns().size()));
    }
    Row row{std::move(records[r])};
    if (!std::isfinite(row.number("index")))
      throw std::runtime_error(fmt::format("{}: line {}: index is not a number", source, r + 1));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string info_json(const SweepInfo& info) {
  nlohmann::ordered_json j = {
      {"format", "tactile-sweep/1"}, {"seed", info.seed},
      {"scenarios", info.scenarios}, {"max_sim_time_s", info.max_sim_time_s},
      {"shard", info.shard},         {"shards", info.shards},
      {"stopped", info.stopped}};
  // Only for a lab's sensor: every other sweep.json keeps its bytes.
  if (!info.calibration.empty()) j["calibration"] = info.calibration;
  return j.dump(2) + "\n";
}

SweepInfo parse_info(const std::string& text, const std::string& source) {
  try {
    const json j = json::parse(text);
    if (need(j, "format") != "tactile-sweep/1")
      throw std::runtime_error("format is not tactile-sweep/1");
    SweepInfo info;
    info.seed = need(j, "seed").get<std::uint64_t>();
    info.scenarios = need(j, "scenarios").get<std::uint64_t>();
    info.max_sim_time_s = need(j, "max_sim_time_s").get<double>();
    info.shard = need(j, "shard").get<int>();
    info.shards = need(j, "shards").get<int>();
    info.stopped = need(j, "stopped").get<bool>();
    info.calibration = j.value("calibration", std::string());
    return info;
  } catch (const std::exception& e) {
    throw std::runtime_error(source + ": " + e.what());
  }
}

std::string summary_markdown(const std::vector<Row>& rows, const SweepInfo& info) {
  std::string out = fmt::format("# Sweep: seed {}, {} scenarios drawn", info.seed, info.scenarios);
  if (info.max_sim_time_s > 0)
    out += fmt::format(", runs cut at {} s simulated", info.max_sim_time_s);
  out += "\n";
  if (!info.calibration.empty())
    out += fmt::format("\nEvery scenario renders the lab's sensor of `{}`.\n", info.calibration);
  if (info.stopped) out += "\nStopped by a signal before every scenario ran.\n";
  std::vector<std::string> methods;
  for (const Row& r : rows) {
    if (std::find(methods.begin(), methods.end(), r.at("method")) == methods.end())
      methods.push_back(r.at("method"));
  }
  std::sort(methods.begin(), methods.end());
  for (const std::string& method : methods) {
    std::vector<const Row*> mine;
    for (const Row& r : rows) {
      if (r.at("method") == method) mine.push_back(&r);
    }
    const auto count = [&](auto pred) {
      return static_cast<std::size_t>(std::count_if(mine.begin(), mine.end(), pred));
    };
    const std::size_t n = mine.size();
    const std::size_t ran = count([](const Row* r) { return r->at("exit_status") == "0"; });
    const auto share = [&](std::size_t k) {
      return fmt::format("{} of {} ({:.1f} %)", k, n,
                         n ? 100.0 * static_cast<double>(k) / static_cast<double>(n) : 0.0);
    };
    out += fmt::format("\n## Method `{}`: {} scenarios\n\n", method, n);
    out += "| score | n | median | 5th pct | 95th pct |\n|---|---|---|---|---|\n";
    const auto score_row = [&](const char* score) {
      std::vector<double> v;
      for (const Row* r : mine) {
        const double x = r->number(score);
        if (std::isfinite(x)) v.push_back(x);
      }
      if (v.empty()) {
        out += fmt::format("| {} | 0 | - | - | - |\n", score);
        return;
      }
      out += fmt::format("| {} | {} | {} | {} | {} |\n", score, v.size(),
                         number_text(percentile(v, 0.5)), number_text(percentile(v, 0.05)),
                         number_text(percentile(v, 0.95)));
    };
    for (const char* score :
         {"precision", "recall", "ideal_precision", "ideal_recall", "precision_without_edges",
          "recall_without_edges", "ideal_precision_without_edges", "ideal_recall_without_edges",
          "incipient_lead_frames", "incipient_episodes", "incipient_detected", "tight_cycle_error",
          "tight_time_error_s", "tight_error_deg", "max_fz_N", "false_slips", "recompressions",
          "over_events"}) {
      score_row(score);
    }
    // The grip against the least that holds (docs/rig.md, "The grip's truth").
    for (const char* score : {"grip_ratio_p50", "grip_ratio_p95", "grip_instant_ratio_p50",
                              "cap_slide_carry_mm", "peak_grip_over_crush"}) {
      score_row(score);
    }
    out += "\n| outcome | scenarios |\n|---|---|\n";
    out += fmt::format("| rig failed (a row with its exit status) | {} |\n", share(n - ran));
    out += fmt::format("| completed | {} |\n",
                       share(count([](const Row* r) { return r->at("completed") == "true"; })));
    out += fmt::format(
        "| aborted | {} |\n",
        share(count([](const Row* r) { return r->at("end_reason").rfind("aborted", 0) == 0; })));
    out += fmt::format("| dropped | {} |\n",
                       share(count([](const Row* r) { return r->at("dropped") == "true"; })));
    out += fmt::format("| OVER raised | {} |\n",
                       share(count([](const Row* r) { return r->number("over_events") > 0; })));
    out += fmt::format(
        "| grasp classified on the lift | {} |\n",
        share(count([](const Row* r) { return r->at("grasp_classified") == "grasp"; })));
    out += fmt::format(
        "| release classified at the bottle | {} |\n",
        share(count([](const Row* r) { return r->at("release_classified") == "release"; })));
    out +=
        fmt::format("| tight in the true cycle | {} |\n",
                    share(count([](const Row* r) { return r->number("tight_cycle_error") == 0; })));
    out += fmt::format("| fragile object broken | {} |\n",
                       share(count([](const Row* r) { return r->at("broken") == "true"; })));
    out += case_table(mine);
    out += hold_table(mine);
    out += disturbance_table(mine);
  }
  return out;
}

}  // namespace tactile::rig::sweep
