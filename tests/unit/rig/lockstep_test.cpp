// The lockstep runner on the bundled default scenario: the paper's experiment end to end with
// the real measurement and control cores, the report's keys, and determinism for a seed.
#include "tactile/rig/lockstep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tactile/rig/control_link.hpp"
#include "tactile/rig/scenario_run.hpp"

namespace tactile::rig {
namespace {

const std::filesystem::path kDir = TACTILE_RIG_SCENARIOS;
const std::filesystem::path kTestScenarios = TACTILE_TEST_SCENARIOS;

TEST(Lockstep, DefaultScenarioTellsThePapersStory) {
  const LockstepResult r = run_lockstep(load_scenario(kDir / "default.yaml"));
  const Report& rep = r.report;
  EXPECT_TRUE(r.physics_finite);
  EXPECT_TRUE(rep.completed) << rep.end_reason;
  EXPECT_FALSE(rep.dropped);
  EXPECT_EQ(rep.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(rep.release_classified, std::optional<std::string>("release"));
  ASSERT_TRUE(rep.tightened_cycle.has_value());
  EXPECT_EQ(rep.tightened_cycle, rep.true_tight_cycle);
  EXPECT_EQ(*rep.tightened_cycle, 3);
  EXPECT_EQ(rep.over_events, 0);
  EXPECT_NEAR(rep.final_cap_angle_deg, 240.0, 1.0);
  // 20 g at mu_s 0.8: a fraction of a newton per fingertip, F2 allows tens.
  EXPECT_TRUE(rep.hold.holdable);
  EXPECT_NEAR(rep.hold.grip_needed_n, 0.020 * (9.81 + rep.hold.peak_accel_mps2) / 1.6, 1e-12);
  // "Tight" a few frames after the cap met its stop (0.03 s at 100 fps), the wrist turned on
  // by under a degree (0.25 rad/s).
  ASSERT_TRUE(rep.tight_time_error_s && rep.tight_error_deg);
  EXPECT_GE(*rep.tight_time_error_s, 0.0);
  EXPECT_LE(*rep.tight_time_error_s, 0.5);
  EXPECT_GE(*rep.tight_error_deg, 0.0);
  EXPECT_LE(*rep.tight_error_deg, 1.0);
  EXPECT_GE(rep.slip.precision, 0.95);
  EXPECT_GE(rep.slip.recall, 0.95);
  EXPECT_LE(rep.slip.latency_frames_p99, 2.0);
  // The measurement is within a few hundredths of an ideal sensor (the paper's test on the true
  // shear displacements): what is left of the gap to 1 is the test's, not the measurement's.
  EXPECT_GE(rep.slip.precision, rep.slip.ideal_precision - 0.03);
  EXPECT_GE(rep.slip.recall, rep.slip.ideal_recall - 0.03);
  EXPECT_LE(rep.force_rmse_normal_N, 0.02 * rep.normal_full_scale_N);
  EXPECT_GT(rep.slip.onsets, 10U);
  // The series for the plots.
  EXPECT_EQ(r.series.frames.size(), rep.frames);
  EXPECT_FALSE(r.series.snapshots.empty());
}

// The paper's feeler element in the optics (docs/rig.md, "The feeler element"): the default
// scenario's outcomes hold, and the truth's displacement is the cluster's own centroid.
TEST(Lockstep, DefaultScenarioWithTheFeelerElementCompletes) {
  Scenario s = load_scenario(kDir / "default.yaml");
  s.optics.element_model = ElementModel::kFeelers;
  const Report rep = run_lockstep(s).report;
  EXPECT_TRUE(rep.completed) << rep.end_reason;
  EXPECT_FALSE(rep.dropped);
  EXPECT_EQ(rep.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(rep.release_classified, std::optional<std::string>("release"));
  EXPECT_EQ(rep.tightened_cycle, rep.true_tight_cycle);
  EXPECT_EQ(rep.over_events, 0);
  EXPECT_LE(rep.force_rmse_normal_N, 0.02 * rep.normal_full_scale_N);
}

// The grip's truth on the default scenario (docs/rig.md, "The grip's truth"): the paper's grip
// holds the cap with more than the least that holds, the cap barely slides in the fingers while
// carried, and every re-compression is counted under its stage.
TEST(Lockstep, DefaultScenarioGripIsAboveTheLeastThatHolds) {
  LockstepOptions o;
  o.record_series = false;
  const Report rep = run_lockstep(load_scenario(kDir / "default.yaml"), o).report;
  ASSERT_TRUE(rep.completed) << rep.end_reason;
  const GripMetrics& g = rep.grip;
  EXPECT_GT(g.held_frames, 100U);
  EXPECT_GT(g.ratio_p50, 1.0);
  EXPECT_GE(g.ratio_p95, g.ratio_p50);
  EXPECT_GE(g.ratio_max, g.ratio_p95);
  // The instant's need is never above the steady one around it.
  EXPECT_GE(g.instant_ratio_p50, g.ratio_p50);
  // The carry's largest need is about the report's peak-acceleration bound.
  EXPECT_LE(g.steady_need_max_N, 1.5 * rep.hold.grip_needed_n);
  EXPECT_GT(g.steady_need_max_N, rep.hold.grip_needed_n / 1.5);
  EXPECT_TRUE(std::isfinite(g.cap_slide_carry_mm));
  EXPECT_GE(g.cap_slide_carry_mm, 0.0);
  EXPECT_LT(g.cap_slide_carry_mm, 1.0);
  int by_stage = 0;
  for (const int n : rep.recompressions_by_phase)
    by_stage += n;
  EXPECT_EQ(by_stage, rep.recompressions);
}

// A pull on the cap during the carry and a fragile cap (docs/rig.md, "Disturbances and fragile
// objects"): the pull starts 0.5 s into TRANSPORT and the truth's need carries it; the paper's grip
// (several newtons per fingertip) crushes a cap that breaks at 2 N (the report's fragile.broken;
// completed stays the controller's), and leaves one that breaks just above the grip's peak whole.
TEST(Lockstep, APullDuringTheCarryAndAFragileCap) {
  Scenario sc = load_scenario(kDir / "default.yaml");
  sc.world.disturbance.pull = {0.2, {0, 0, -1}, kNotYet, 0.0, 1.0};
  sc.disturbance_start[static_cast<std::size_t>(DisturbanceKind::kPull)] = {"TRANSPORT", 0.5};
  sc.world.cap.crush_force_n = 2.0;
  LockstepOptions o;
  o.record_series = false;
  const Report crushed = run_lockstep(sc, o).report;
  ASSERT_TRUE(crushed.disturbance && crushed.fragile);
  const double start = crushed.disturbance->pull.start_s;
  ASSERT_TRUE(std::isfinite(start)) << "the carry came";
  EXPECT_GT(start, 5.0);
  EXPECT_DOUBLE_EQ(crushed.hold.grip_needed_n,
                   (0.020 * (9.81 + crushed.hold.peak_accel_mps2) + 0.2) / 1.6);
  // The need while carried includes the pull (the weight alone asks for 0.12 N).
  EXPECT_GT(crushed.grip.steady_need_max_N, 0.9 * (0.020 * 9.81 + 0.2) / 1.6);
  EXPECT_FALSE(crushed.dropped);
  EXPECT_TRUE(crushed.fragile->broken);
  EXPECT_GT(crushed.fragile->peak_grip_n, 2.0);
  EXPECT_GT(crushed.fragile->broken_at_s, 0.0);
  EXPECT_LT(crushed.fragile->broken_at_s, start) << "crushed by the grasp, before the carry";
  EXPECT_TRUE(crushed.completed) << "the controller finished its task; broken says the rest";
  EXPECT_EQ(crushed.end_reason, "done");
  const nlohmann::json j = nlohmann::json::parse(report_json(crushed));
  EXPECT_EQ(j.at("disturbance").at("pull").at("start_s"), start);
  EXPECT_EQ(j.at("disturbance").at("pull").at("force_N"), 0.2);
  EXPECT_FALSE(j.at("disturbance").contains("knock"));
  EXPECT_EQ(j.at("fragile").at("broken"), true);
  EXPECT_EQ(j.at("fragile").at("crush_force_N"), 2.0);

  sc.world.cap.crush_force_n = 1.01 * crushed.fragile->peak_grip_n;
  const Report whole = run_lockstep(sc, o).report;
  ASSERT_TRUE(whole.fragile);
  EXPECT_FALSE(whole.fragile->broken);
  EXPECT_EQ(whole.fragile->peak_grip_n, crushed.fragile->peak_grip_n) << "the crush force is truth";
  EXPECT_TRUE(whole.completed) << whole.end_reason;
  EXPECT_TRUE(nlohmann::json::parse(report_json(whole)).at("fragile").at("broken_at_s").is_null());
}

// Without disturbance and crush force the report has neither key: every other report keeps its
// bytes.
TEST(Lockstep, NoDisturbanceNoKey) {
  Report rep;
  const nlohmann::json j = nlohmann::json::parse(report_json(rep));
  EXPECT_FALSE(j.contains("disturbance"));
  EXPECT_FALSE(j.contains("fragile"));
}

// The margin grip (docs/control.md, "The margin grip") on the default scenario, as
// whole-story.yaml holds it: grasp classified on the lift, a re-compression as the weight arrives
// in the lift's loading phase, release at the bottle, tight in the true cycle, with no drop and no
// OVER, and the cap held closer to the least grip that holds than by the paper's. One key (grip:
// paper) gives default.yaml's run exactly. Not shown since the loading phase (2026-11-28): a
// re-compression from the arm's vibration during the carry (the grip, about 2.4 times the least,
// holds through it; docs/control.md, "The whole story in one run").
TEST(Lockstep, WholeStoryScenarioHoldsWithLessGripAndIsThePapersRunWithOneKey) {
  LockstepOptions o;
  o.record_series = false;
  const Scenario paper = load_scenario(kDir / "default.yaml");
  Scenario margin = load_scenario(kDir / "whole-story.yaml");
  EXPECT_EQ(margin.grip, "margin");
  const control::Config cfg = scenario_controller_config(margin);
  const Report p = run_lockstep(paper, o).report;
  LockstepOptions with_series;
  const LockstepResult run = run_lockstep(margin, with_series);
  const Report& m = run.report;
  margin.grip = "paper";
  EXPECT_EQ(report_json(run_lockstep(margin, o).report), report_json(p));
  const nlohmann::json stages = nlohmann::json::parse(report_json(m)).at("recompressions_by_stage");
  const auto lift = std::find_if(
      run.series.frames.begin(), run.series.frames.end(),
      [](const auto& f) { return f.phase == static_cast<std::uint8_t>(control::Phase::kLift); });
  ASSERT_NE(lift, run.series.frames.end());
  const double loaded_s = lift->t + cfg.grip_loading_distance_m / cfg.grip_loading_speed_mps;
  EXPECT_TRUE(std::any_of(run.series.events.begin(), run.series.events.end(),
                          [&](const auto& e) {
                            return e.kind_name == "RECOMPRESS" && e.phase == "LIFT" &&
                                   e.t <= loaded_s + cfg.grip_ff_lead_s;
                          }))
      << "no re-compression as the weight arrived (the lift from " << lift->t
      << " s): " << stages.dump();
  EXPECT_EQ(m.controller.grip, "margin");
  EXPECT_EQ(p.controller.grip, "paper");
  EXPECT_TRUE(m.completed) << m.end_reason;
  EXPECT_FALSE(m.dropped);
  EXPECT_EQ(m.over_events, 0);
  EXPECT_EQ(m.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(m.release_classified, std::optional<std::string>("release"));
  ASSERT_TRUE(m.tightened_cycle.has_value());
  EXPECT_EQ(m.tightened_cycle, m.true_tight_cycle);
  ASSERT_GT(m.grip.held_frames, 100U);
  EXPECT_GT(m.grip.ratio_p50, 1.0) << "no frame is held with less than the least that holds";
  EXPECT_LT(m.grip.ratio_p50, p.grip.ratio_p50);
  EXPECT_LT(m.grip.cap_slide_carry_mm, 1.0);
}

// A cap held to the table (the seed-20 sweep's scenario 7) rises off it by the anchor's stretch
// for a few frames under the grip: the anchor holds it, not the fingers, so no frame is held and
// the grip's ratios are null.
TEST(Lockstep, ACapAnchoredToTheTableIsNeverHeldByTheFingers) {
  LockstepOptions o;
  o.record_series = false;
  const Report rep =
      run_lockstep(load_scenario(kTestScenarios / "anchored-cap-pulled-up.yaml"), o).report;
  EXPECT_EQ(rep.scenario_case, "cap_held");
  EXPECT_EQ(rep.grip.held_frames, 0U);
  EXPECT_EQ(rep.grip.cap_slide_carry_mm, 0.0);
  EXPECT_TRUE(nlohmann::json::parse(report_json(rep)).at("grip").at("ratio_p50").is_null());
}

// A heavy cap under strong vibration (the seed-20 sweep's scenario 5, one of its 40 that
// aborted): held on damped feelers it no longer rings, the lowering reaches the bottle before
// the release is classified, and Phase II finds the cap where it was let go.
TEST(Lockstep, HeavyVibratingCapFromTheSweepCompletes) {
  LockstepOptions o;
  o.record_series = false;
  const Report rep =
      run_lockstep(load_scenario(kTestScenarios / "heavy-vibrating-cap.yaml"), o).report;
  EXPECT_TRUE(rep.completed) << rep.end_reason;
  EXPECT_EQ(rep.end_reason, "done");
  EXPECT_FALSE(rep.dropped);
  EXPECT_EQ(rep.release_classified, std::optional<std::string>("release"));
  ASSERT_TRUE(rep.tightened_cycle.has_value());
  EXPECT_EQ(rep.tightened_cycle, rep.true_tight_cycle);
  EXPECT_EQ(rep.over_events, 0);
  // The grip stays far from F2 (2.5 N): 2.40 N while the cap rang, 1.53 N since.
  EXPECT_LT(rep.max_fz_N, 2.0);
  // 4,660 false slips while it rang; 73 since (the paper's rule at the lift-off and the release).
  EXPECT_LT(rep.slip.false_positives, 200U);
}

// The sweep's negative cases (docs/slip.md, "Negative cases") on the default scenario. The
// bottle displaced 100 mm: the cap lowered over the controller's place meets nothing above the
// lowering's limit (0.09 m, above the table), so no release may be classified and the fingers
// may not open; the report says which happened.
TEST(Lockstep, DisplacedBottleNoReleaseAndTheReportSaysSo) {
  Scenario s = load_scenario(kDir / "default.yaml");
  s.world.bottle.displaced_x_m = 0.1;
  s.controller.emplace_back("lower_limit_m", 0.09);
  LockstepOptions o;
  o.record_series = false;
  const Report rep = run_lockstep(s, o).report;
  EXPECT_EQ(rep.scenario_case, "bottle_displaced");
  EXPECT_EQ(rep.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(rep.release_classified, std::nullopt);
  EXPECT_FALSE(rep.opened_in_air);
  EXPECT_FALSE(rep.dropped);
  EXPECT_EQ(rep.negative_case_passed, std::optional<bool>(true));
  EXPECT_EQ(rep.end_reason, "aborted: lowered to lower_limit_m without a negative slip");
  const nlohmann::json j = nlohmann::json::parse(report_json(rep));
  EXPECT_EQ(j.at("case"), "bottle_displaced");
  EXPECT_EQ(j.at("negative_case_passed"), true);
  EXPECT_EQ(j.at("opened_in_air"), false);
}

// The cap held to the table: the lift must not classify a grasp. The paper's rule sees the cap
// slide down the fingertips as the weight's pull and says "grasp"; the report judges whichever
// answer the run gave (run through the lift only).
TEST(Lockstep, HeldCapIsJudgedOnTheLift) {
  Scenario s = load_scenario(kDir / "default.yaml");
  s.world.cap.held_to_table = true;
  s.max_time_s = 12.0;
  LockstepOptions o;
  o.record_series = false;
  const Report rep = run_lockstep(s, o).report;
  EXPECT_EQ(rep.scenario_case, "cap_held");
  EXPECT_FALSE(rep.dropped) << "the cap never left the table";
  ASSERT_TRUE(rep.negative_case_passed.has_value());
  EXPECT_EQ(*rep.negative_case_passed, rep.grasp_classified != "grasp");
  // The rule on its own: a grasp fails, a release or nothing passes.
  Report judged;
  judged.scenario_case = "cap_held";
  for (const auto& [grasp, passed] : std::vector<std::pair<std::optional<std::string>, bool>>{
           {"grasp", false}, {"release", true}, {std::nullopt, true}}) {
    judged.grasp_classified = grasp;
    judge_negative_case(judged);
    EXPECT_EQ(judged.negative_case_passed, std::optional<bool>(passed));
  }
  judged.scenario_case = "bottle_displaced";
  judged.release_classified.reset();
  judged.opened_in_air = true;
  judge_negative_case(judged);
  EXPECT_EQ(judged.negative_case_passed, std::optional<bool>(false)) << "fingers opened";
  judged.scenario_case = "normal";
  judge_negative_case(judged);
  EXPECT_EQ(judged.negative_case_passed, std::nullopt);
}

// The field detector classifies the lift and the lowering from the load transfer
// (docs/slip.md, "Decisions on the field detector"): a 4 g cap, whose slips the paper's rule
// never sees on the lift, is classified a grasp by the weight its fingertips take on, and
// released where its weight goes to the bottle.
TEST(Lockstep, FieldDetectorClassifiesALightCapByItsLoad) {
  Scenario s = load_scenario(kDir / "default.yaml");
  s.world.cap.mass_kg = 0.004;
  s.slip_detector = "field";
  LockstepOptions o;
  o.record_series = false;
  const Report rep = run_lockstep(s, o).report;
  EXPECT_EQ(rep.slip.detector, "field");
  EXPECT_EQ(rep.slip_other.detector, "paper");
  EXPECT_EQ(rep.controller.slip_detector, "field");
  EXPECT_EQ(rep.controller.grip, "paper");
  EXPECT_TRUE(rep.completed) << rep.end_reason;
  EXPECT_EQ(rep.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(rep.release_classified, std::optional<std::string>("release"));
  EXPECT_FALSE(rep.opened_in_air);
  EXPECT_EQ(rep.tightened_cycle, rep.true_tight_cycle);
}

// The negative cases with the field detector: the held cap slips under fingertips that rise
// (put back: no grasp), the displaced bottle takes no load (no release, the fingers stay shut).
TEST(Lockstep, FieldDetectorPassesTheNegativeCases) {
  LockstepOptions o;
  o.record_series = false;
  Scenario held = load_scenario(kDir / "default.yaml");
  held.world.cap.held_to_table = true;
  held.max_time_s = 12.0;
  held.slip_detector = "field";
  const Report h = run_lockstep(held, o).report;
  EXPECT_NE(h.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(h.negative_case_passed, std::optional<bool>(true));

  Scenario displaced = load_scenario(kDir / "default.yaml");
  displaced.world.bottle.displaced_x_m = 0.1;
  displaced.controller.emplace_back("lower_limit_m", 0.09);
  displaced.slip_detector = "field";
  const Report d = run_lockstep(displaced, o).report;
  EXPECT_EQ(d.grasp_classified, std::optional<std::string>("grasp"));
  EXPECT_EQ(d.release_classified, std::nullopt);
  EXPECT_FALSE(d.opened_in_air);
  EXPECT_EQ(d.negative_case_passed, std::optional<bool>(true));
  EXPECT_EQ(d.end_reason, "aborted: lowered to lower_limit_m without the load going to a support");
}

TEST(Lockstep, SameSeedSameReportBytes) {
  Scenario s = load_scenario(kDir / "default.yaml");
  s.max_time_s = 8.0;  // through the grasp, the lift and its slip classification
  LockstepOptions o;
  o.record_series = false;
  const std::string a = report_json(run_lockstep(s, o).report);
  const std::string b = report_json(run_lockstep(s, o).report);
  EXPECT_EQ(a, b);
  s.seed = 2;
  EXPECT_NE(report_json(run_lockstep(s, o).report), a);
}

// INTERFACES.md section 4: every key, with its JSON type; ours beside them.
TEST(Lockstep, ReportHasTheInterfaceKeys) {
  Report rep;
  rep.grasp_classified.emplace("grasp");
  rep.tightened_cycle = 3;
  rep.slip.true_positives = 7;
  rep.slip_other.detector = "field";
  rep.seed = 5;
  rep.end_reason = "done";
  const nlohmann::json j = nlohmann::json::parse(report_json(rep));
  ASSERT_TRUE(j.is_object());
  EXPECT_TRUE(j.at("completed").is_boolean());
  EXPECT_TRUE(j.at("dropped").is_boolean());
  EXPECT_EQ(j.at("grasp_classified"), "grasp");
  EXPECT_TRUE(j.at("release_classified").is_null());
  EXPECT_TRUE(j.at("recompressions").is_number_integer());
  EXPECT_TRUE(j.at("twist_cycles").is_number_integer());
  EXPECT_TRUE(j.at("tightened_cycle").is_number_integer());
  EXPECT_EQ(j.at("tightened_cycle"), 3);
  EXPECT_TRUE(j.at("true_tight_cycle").is_null());
  EXPECT_TRUE(j.at("max_fz_N").is_number());
  EXPECT_TRUE(j.at("over_events").is_number_integer());
  const nlohmann::json& slip = j.at("slip");
  ASSERT_TRUE(slip.is_object());
  for (const char* key : {"precision", "recall"}) {
    EXPECT_TRUE(slip.at(key).is_number()) << key;
  }
  // Frame counts, written as the integers they are (docs/rig.md's example).
  for (const char* key : {"latency_frames_p50", "latency_frames_p99"}) {
    EXPECT_TRUE(slip.at(key).is_number_integer()) << key;
  }
  const nlohmann::json& rmse = j.at("force_rmse_N");
  ASSERT_TRUE(rmse.is_object());
  EXPECT_TRUE(rmse.at("normal").is_number());
  EXPECT_TRUE(rmse.at("shear").is_number());
  EXPECT_TRUE(j.at("latency_ms").is_null());  // lockstep: no wire, no latency
  // Ours, beside the interface's.
  for (const char* key :
       {"true_positives", "false_positives", "false_negatives", "onsets", "missed_onsets"}) {
    EXPECT_TRUE(slip.at(key).is_number_unsigned()) << key;
  }
  EXPECT_EQ(slip.at("true_positives"), 7);
  const nlohmann::json& ideal = slip.at("ideal_sensor");
  ASSERT_TRUE(ideal.is_object());
  EXPECT_TRUE(ideal.at("precision").is_number());
  EXPECT_TRUE(ideal.at("recall").is_number());
  const nlohmann::json& lockstep = j.at("lockstep");
  ASSERT_TRUE(lockstep.is_object());
  EXPECT_EQ(lockstep.at("seed"), 5);
  EXPECT_TRUE(lockstep.at("seed").is_number_unsigned());
  EXPECT_TRUE(lockstep.at("frames").is_number_unsigned());
  for (const char* key :
       {"sim_time_s", "physics_step_s", "final_cap_angle_deg", "normal_full_scale_N"}) {
    EXPECT_TRUE(lockstep.at(key).is_number()) << key;
  }
  EXPECT_EQ(lockstep.at("end_reason"), "done");
  // The interface's keys first, in its order; ours after them.
  const nlohmann::ordered_json in_order = nlohmann::ordered_json::parse(report_json(rep));
  std::vector<std::string> keys;
  for (const auto& [key, value] : in_order.items())
    keys.push_back(key);
  // Both detectors are scored: the run's under `slip`, the other under `slip_other`.
  EXPECT_EQ(in_order.at("slip").at("detector"), "paper");
  EXPECT_EQ(in_order.at("slip_other").at("detector"), "field");
  for (const char* key : {"slip", "slip_other"}) {
    const auto& s = in_order.at(key);
    EXPECT_TRUE(s.at("without_edges").at("precision").is_number()) << key;
    EXPECT_TRUE(s.at("ideal_sensor").at("without_edges").at("recall").is_number()) << key;
    EXPECT_TRUE(s.at("edge_frames").is_number_unsigned()) << key;
  }
  EXPECT_EQ(keys, (std::vector<std::string>{"completed",
                                            "dropped",
                                            "grasp_classified",
                                            "release_classified",
                                            "recompressions",
                                            "twist_cycles",
                                            "tightened_cycle",
                                            "true_tight_cycle",
                                            "max_fz_N",
                                            "over_events",
                                            "slip",
                                            "force_rmse_N",
                                            "latency_ms",
                                            "slip_other",
                                            "lockstep",
                                            "tight_time_error_s",
                                            "tight_error_deg",
                                            "case",
                                            "negative_case_passed",
                                            "opened_in_air",
                                            "holdable",
                                            "hold",
                                            "controller",
                                            "grip",
                                            "recompressions_by_stage",
                                            "machine"}));
  EXPECT_TRUE(j.at("machine").is_null());  // lockstep: the machine's load explains nothing
  EXPECT_EQ(j.at("case"), "normal");
  EXPECT_TRUE(j.at("negative_case_passed").is_null());
  EXPECT_EQ(j.at("opened_in_air"), false);
  EXPECT_TRUE(j.at("holdable").is_boolean());
  for (const char* key : {"peak_accel_mps2", "grip_needed_N", "grip_allowed_N"})
    EXPECT_TRUE(j.at("hold").at(key).is_number()) << key;
  EXPECT_EQ(j.at("controller"), (nlohmann::json{{"slip_detector", "paper"}, {"grip", "paper"}}));
  // Null when either instant is missing; numbers when both are there.
  EXPECT_TRUE(j.at("tight_time_error_s").is_null());
  EXPECT_TRUE(j.at("tight_error_deg").is_null());
  rep.tight_time_error_s = 0.25;
  rep.tight_error_deg = 12.5;
  const nlohmann::json k = nlohmann::json::parse(report_json(rep));
  EXPECT_EQ(k.at("tight_time_error_s"), 0.25);
  EXPECT_EQ(k.at("tight_error_deg"), 12.5);
}

// A distributed run's latency is an object of three numbers; a number that is not finite is
// null (the JSON has no other way to say it), never invalid JSON.
TEST(Lockstep, ReportLatencyAndNonFiniteNumbers) {
  Report rep;
  rep.latency_ms = Report::Latency{0.6, 1.8, 4.0};
  rep.max_fz_N = std::numeric_limits<double>::quiet_NaN();
  rep.force_rmse_shear_N = std::numeric_limits<double>::infinity();
  const nlohmann::json j = nlohmann::json::parse(report_json(rep));
  const nlohmann::json& latency = j.at("latency_ms");
  ASSERT_TRUE(latency.is_object());
  EXPECT_DOUBLE_EQ(latency.at("p50").get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(latency.at("p99").get<double>(), 1.8);
  EXPECT_DOUBLE_EQ(latency.at("max").get<double>(), 4.0);
  EXPECT_TRUE(j.at("machine").is_null());
  // The machine over the run, and whether it explains the latency (steal above 5 %).
  rep.machine = tactile::util::MachineLoad{7.5, 1.25, 2};
  const nlohmann::json m = nlohmann::json::parse(report_json(rep)).at("machine");
  EXPECT_EQ(m, (nlohmann::json{{"cpu_steal_pct", 7.5},
                               {"load_average_1m", 1.25},
                               {"cores", 2},
                               {"explains_latency", true}}));
  EXPECT_TRUE(j.at("max_fz_N").is_null());
  EXPECT_TRUE(j.at("force_rmse_N").at("shear").is_null());
  EXPECT_TRUE(j.at("force_rmse_N").at("normal").is_number());
}

// The report's numbers read back as the very doubles of the Report (shortest round trip).
TEST(Lockstep, ReportNumbersReadBackExactly) {
  Report rep;
  rep.max_fz_N = 0.8516666666666668;
  rep.slip.precision = 0.9518900343642611;
  rep.final_cap_angle_deg = 240.00000000000009;
  rep.physics_step_s = 1e-4;
  const nlohmann::json j = nlohmann::json::parse(report_json(rep));
  EXPECT_EQ(j.at("max_fz_N").get<double>(), rep.max_fz_N);
  EXPECT_EQ(j.at("slip").at("precision").get<double>(), rep.slip.precision);
  EXPECT_EQ(j.at("lockstep").at("final_cap_angle_deg").get<double>(), rep.final_cap_angle_deg);
  EXPECT_EQ(j.at("lockstep").at("physics_step_s").get<double>(), rep.physics_step_s);
}

}  // namespace
}  // namespace tactile::rig
