// The one scorer of a rig run (docs/rig.md, "Scoring"): the lockstep runner feeds it each frame
// whole and at once; the real-time rig feeds it the truth when it renders, the measured frames
// and the events later, as they arrive over the wire. One recorded stream fed both ways gives the
// same metrics.
#include "tactile/rig/scoring.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <vector>

#include "tactile/rig/sensors.hpp"
#include "tactile/util/random.hpp"

namespace tactile::rig {
namespace {

const std::filesystem::path kDir = TACTILE_RIG_SCENARIOS;

// One frame of a recorded run: the truth, both fingertips' measured readings, the controller's
// state when the frame was taken (`phase_taken`) and after it (`controller`), and its events.
struct RecordedFrame {
  double t = 0;
  GroundTruth truth;
  std::array<std::array<ElementReading, kElementsPerFingertip>, kFingertips> measured{};
  control::Phase phase_taken = control::Phase::kIdle;
  ControllerState controller;
  FramePose pose;
  std::vector<control::Event> events;
};

// A synthetic stream with the statistics that matter to the scorer: slip episodes per element
// (a Markov chain), a measurement that mostly but not always agrees with them, forces near F1
// and F2, a switch to Phase II (the threshold changes) and the events the report counts.
std::vector<RecordedFrame> synthetic_stream(std::size_t frames) {
  util::Random rng(20261125);
  std::vector<RecordedFrame> stream(frames);
  std::array<std::array<bool, kElementsPerFingertip>, kFingertips> sliding{};
  double wrist_yaw = 0;
  for (std::size_t n = 0; n < frames; ++n) {
    RecordedFrame& f = stream[n];
    // The wrist turns clockwise (tightening) for 13 frames of 20, then back by half as much.
    wrist_yaw += n % 20 < 13 ? -0.01 : 0.005;
    f.pose.wrist_yaw_rad = wrist_yaw;
    f.t = static_cast<double>(n + 1) / 100.0;
    const bool twist = n >= frames / 2;
    f.phase_taken = n < frames / 4 ? control::Phase::kLift
                    : twist        ? control::Phase::kTwistTurn
                                   : control::Phase::kTransport;
    f.controller = {f.phase_taken,
                    twist ? static_cast<std::uint32_t>(1 + (n - frames / 2) / 50) : 0U};
    f.truth.sim_time_s = f.t;
    f.truth.cap_angle_deg = static_cast<double>(n) * 0.5;
    f.truth.cap_tight = n >= frames - 30;
    for (std::size_t i = 0; i < kFingertips; ++i) {
      f.pose.fingertip_x_m[i] = 0.01 * static_cast<double>(n) + 0.001 * static_cast<double>(i);
      for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
        ElementTruth& et = f.truth.fingertips[i].elements[k];
        et.id = static_cast<std::uint32_t>(k);
        et.visible = k < 12 || rng.uniform() < 0.1;
        et.contact = et.visible;
        et.fz_n = et.visible ? rng.uniform(0.05, 1.2) : 0.0;
        et.fx_n = rng.uniform(-0.1, 0.1);
        et.fy_n = rng.uniform(-0.1, 0.1);
        et.ux_mm = rng.uniform(-0.2, 0.2);
        et.uy_mm = rng.uniform(-0.2, 0.2);
        const double flip = sliding[i][k] ? 0.3 : 0.05;
        if (et.visible && rng.uniform() < flip) sliding[i][k] = !sliding[i][k];
        if (!et.visible) sliding[i][k] = false;
        et.sliding = sliding[i][k];
        ElementReading& r = f.measured[i][k];
        r.id = et.id;
        r.contact = et.visible ? rng.uniform() < 0.95 : rng.uniform() < 0.03;
        r.has_displacement = r.contact && rng.uniform() < 0.9;
        const bool agree = rng.uniform() < 0.85;
        const double d = (et.sliding == agree) ? rng.uniform(0.05, 0.2) : rng.uniform(0, 0.02);
        r.dx_mm = d * 0.6;
        r.dy_mm = -d * 0.8;
        r.fz = et.fz_n + 0.01 * rng.normal();
        r.fx = et.fx_n + 0.005 * rng.normal();
        r.fy = et.fy_n + 0.005 * rng.normal();
        r.ux_mm = et.ux_mm;
        r.uy_mm = et.uy_mm;
      }
    }
    const auto event = [&f](control::EventKind kind, std::uint32_t cycle, const char* text) {
      control::Event e;
      e.kind = kind;
      e.phase = f.controller.phase;
      e.cycle = cycle;
      e.text = text;
      f.events.push_back(e);
    };
    if (n == 20) event(control::EventKind::kGraspClassified, 0, "");
    if (n == 21) event(control::EventKind::kRecompress, 0, "");
    if (n == frames / 3) event(control::EventKind::kRecompress, 0, "");
    if (n == frames - 25) event(control::EventKind::kCapTight, f.controller.twist_cycle, "");
    if (n == frames - 5) event(control::EventKind::kDone, f.controller.twist_cycle, "");
  }
  return stream;
}

LockstepResult empty_run() {
  LockstepResult run;
  const Scenario sc = load_scenario(kDir / "default.yaml");
  const World world(sc.world);
  run.calibrations = simulated_calibrations(sc, sc.camera, world.element_normals());
  return run;
}

// As run_lockstep does: frames counted from 1, each frame's truth, measurements and events at
// once.
LockstepResult score_as_lockstep(const std::vector<RecordedFrame>& stream,
                                 const control::Config& cfg) {
  LockstepResult run = empty_run();
  RunScorer scorer(run, cfg, true);
  std::uint64_t frame = 0;
  for (const RecordedFrame& f : stream) {
    ++frame;
    scorer.add_truth(frame, f.t, f.truth, f.controller, f.pose);
    for (std::size_t i = 0; i < kFingertips; ++i)
      scorer.add_measurement(i, frame, f.measured[i], f.truth.fingertips[i], f.phase_taken, {});
    for (const control::Event& e : f.events)
      scorer.add_event(e, f.t);
  }
  scorer.finish(false, static_cast<double>(frame) / 100.0, frame);
  return run;
}

// As run_realtime does: frames counted from 0; the truth when the frame is rendered; each
// fingertip's measured frame some frames later (the right one sometimes first) and the events
// after the measurements of their frame.
LockstepResult score_as_realtime(const std::vector<RecordedFrame>& stream,
                                 const control::Config& cfg) {
  LockstepResult run = empty_run();
  RunScorer scorer(run, cfg, true);
  struct Arrival {
    std::size_t index;
    std::size_t fingertip;
  };
  std::deque<Arrival> in_flight;
  std::vector<int> delivered(stream.size(), 0);
  const auto deliver = [&](const Arrival& a) {
    const RecordedFrame& f = stream[a.index];
    scorer.add_measurement(a.fingertip, a.index, f.measured[a.fingertip],
                           f.truth.fingertips[a.fingertip], f.phase_taken, {});
    if (++delivered[a.index] == 2) {  // both fingertips of the frame are in: its events follow
      for (const control::Event& e : f.events)
        scorer.add_event(e, f.t + 0.004);
    }
  };
  for (std::size_t n = 0; n < stream.size(); ++n) {
    scorer.add_truth(n, stream[n].t, stream[n].truth, stream[n].controller, stream[n].pose);
    const std::size_t first = n % 3 == 0 ? 1 : 0;
    in_flight.push_back({n, first});
    in_flight.push_back({n, 1 - first});
    while (in_flight.size() > 6) {  // three frames in flight
      deliver(in_flight.front());
      in_flight.pop_front();
    }
  }
  while (!in_flight.empty()) {
    deliver(in_flight.front());
    in_flight.pop_front();
  }
  scorer.finish(false, static_cast<double>(stream.size()) / 100.0, stream.size());
  return run;
}

TEST(Scoring, LockstepAndRealTimeOrderGiveTheSameMetrics) {
  const control::Config cfg;
  const std::vector<RecordedFrame> stream = synthetic_stream(400);
  const LockstepResult a = score_as_lockstep(stream, cfg);
  const LockstepResult b = score_as_realtime(stream, cfg);
  // The stream exercises what it should.
  ASSERT_GT(a.report.slip.true_positives, 100U);
  ASSERT_GT(a.report.slip.false_positives, 10U);
  ASSERT_GT(a.report.slip.false_negatives, 10U);
  ASSERT_GT(a.report.slip.onsets, 50U);
  ASSERT_EQ(a.report.recompressions, 2);
  ASSERT_TRUE(a.report.completed);
  // The cap meets its stop at frame 370 (t 3.71 s), "tight" is declared at frame 375 (3.76 s);
  // the wrist turns toward tightening in frames 371 and 372 (0.02 rad), back in 373 to 375.
  ASSERT_TRUE(a.report.tight_time_error_s && a.report.tight_error_deg);
  EXPECT_NEAR(*a.report.tight_time_error_s, 0.05, 1e-12);
  EXPECT_NEAR(*a.report.tight_error_deg, 0.02 * 180 / std::numbers::pi, 1e-9);
  // In real time the event's time is its arrival (4 ms later here) and the wrist's turn is the
  // truth's then (turning back, so no more); the rest is the same.
  ASSERT_TRUE(b.report.tight_time_error_s && b.report.tight_error_deg);
  EXPECT_NEAR(*b.report.tight_time_error_s, 0.054, 1e-12);
  EXPECT_NEAR(*b.report.tight_error_deg, *a.report.tight_error_deg, 1e-9);
  LockstepResult b_same_arrival = b;
  b_same_arrival.report.tight_time_error_s = a.report.tight_time_error_s;
  // Every metric of the report, as bytes.
  EXPECT_EQ(report_json(a.report), report_json(b_same_arrival.report));
  // And the series: per-frame scores, flags and Fig. 10's x.
  ASSERT_EQ(a.series.frames.size(), b.series.frames.size());
  for (std::size_t n = 0; n < a.series.frames.size(); ++n) {
    const FrameSample& x = a.series.frames[n];
    const FrameSample& y = b.series.frames[n];
    EXPECT_EQ(x.tp, y.tp) << n;
    EXPECT_EQ(x.fp, y.fp) << n;
    EXPECT_EQ(x.fn, y.fn) << n;
    EXPECT_EQ(x.touch, y.touch) << n;
    EXPECT_EQ(x.slip, y.slip) << n;
    EXPECT_EQ(x.over, y.over) << n;
    EXPECT_EQ(x.dy_mm, y.dy_mm) << n;
    EXPECT_EQ(x.max_fz_measured, y.max_fz_measured) << n;
    EXPECT_EQ(x.fingertip_x_m, y.fingertip_x_m) << n;
  }
  EXPECT_EQ(a.series.mismatches.size(), b.series.mismatches.size());
  EXPECT_EQ(a.series.events.size(), b.series.events.size());
}

// TOUCH, SLIP and OVER in the series are the control core's own flags (FlagAnalyzer) of the
// measured frame: TOUCH for F_z above F1 or a slip, OVER above F2.
TEST(Scoring, SeriesFlagsAreTheControllersFlags) {
  control::Config cfg;
  cfg.slip_detector = control::SlipDetectorKind::kPaper;  // one element beyond dr: SLIP
  LockstepResult run = empty_run();
  RunScorer scorer(run, cfg, true);
  GroundTruth gt;
  scorer.add_truth(1, 0.01, gt, {control::Phase::kLift, 0}, {});
  std::array<ElementReading, kElementsPerFingertip> left{}, right{};
  left[0].contact = true;
  left[0].fz = cfg.f2_n + 0.1;  // over F2, so over F1 too
  right[3].contact = true;
  right[3].has_displacement = true;
  right[3].fz = 0.5 * cfg.f1_n;  // below F1, but slipping: TOUCH
  right[3].dy_mm = 2 * cfg.dr_mm;
  scorer.add_measurement(0, 1, left, gt.fingertips[0], control::Phase::kLift, {});
  scorer.add_measurement(1, 1, right, gt.fingertips[1], control::Phase::kLift, {});
  const FrameSample& s = run.series.frames.at(0);
  EXPECT_TRUE(s.touch[0]);
  EXPECT_TRUE(s.over[0]);
  EXPECT_FALSE(s.slip[0]);
  EXPECT_TRUE(s.touch[1]);
  EXPECT_TRUE(s.slip[1]);
  EXPECT_FALSE(s.over[1]);
}

// The series carries each frame's grip truth (the columns grip_need_N, grip_applied_N,
// grip_held): the need, the smaller fingertip's grip, held; a frame without a sample (series off)
// is left alone.
TEST(Scoring, SeriesCarriesTheGripsTruthOfEachFrame) {
  control::Config cfg;
  LockstepResult run = empty_run();
  RunScorer scorer(run, cfg, true);
  GroundTruth gt;
  GripTruth g;
  g.needed_n = 0.25;
  g.applied_n = {0.9, 0.7};
  g.held = true;
  scorer.add_truth(1, 0.01, gt, {control::Phase::kTransport, 0}, {});
  scorer.add_grip(0.01, g);
  scorer.add_truth(2, 0.02, gt, {control::Phase::kLower, 0}, {});
  g.held = false;
  g.applied_n = {0.4, 0.6};
  scorer.add_grip(0.02, g);
  ASSERT_EQ(run.series.frames.size(), 2U);
  EXPECT_EQ(run.series.frames[0].grip_need_n, 0.25);
  EXPECT_EQ(run.series.frames[0].grip_applied_n, 0.7);
  EXPECT_TRUE(run.series.frames[0].grip_held);
  EXPECT_EQ(run.series.frames[1].grip_applied_n, 0.4);
  EXPECT_FALSE(run.series.frames[1].grip_held);
  const std::string csv = series_csv(run.series);
  const std::string header = csv.substr(0, csv.find('\n'));
  EXPECT_TRUE(header.ends_with(",grip_need_N,grip_applied_N,grip_held")) << header;
  EXPECT_NE(csv.find(",0.2500,0.7000,1\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",0.2500,0.4000,0\n"), std::string::npos) << csv;

  LockstepResult quiet = empty_run();
  RunScorer off(quiet, cfg, false);
  off.add_truth(1, 0.01, gt, {control::Phase::kTransport, 0}, {});
  off.add_grip(0.01, g);
  EXPECT_TRUE(quiet.series.frames.empty());
}

// The incipient lead (docs/slip.md, "The incipient lead"): on fingertip 0, twelve elements in
// contact; partial slip (3 of 12 sliding) before gross slip (10 of 12) makes an episode, and the
// run's detector (the paper's rule) leads by the frames from its first slipping element in the
// run-up to the onset.
TEST(Scoring, IncipientLeadCountsFramesFromTheFirstFlagInTheRunUpToGrossSlip) {
  control::Config cfg;
  cfg.slip_detector = control::SlipDetectorKind::kPaper;  // a measured motion beyond dr: a slip
  LockstepResult run = empty_run();
  RunScorer scorer(run, cfg, false);
  const auto in = [](std::uint64_t f, std::uint64_t from, std::uint64_t to) {
    return f >= from && f <= to;
  };
  for (std::uint64_t frame = 1; frame <= 100; ++frame) {
    GroundTruth gt;
    std::array<ElementReading, kElementsPerFingertip> left{}, right{};
    // Partial runs-up and gross onsets by the truth: episodes at 15 (flag at 12: lead 3), 34
    // (nothing before the onset: lead 0) and 54 (flag at 52: lead 2); gross straight from stick
    // at 70 and partial slip that never turns gross at 80-85 are no episodes.
    const bool partial =
        in(frame, 10, 14) || in(frame, 30, 33) || in(frame, 50, 53) || in(frame, 80, 85);
    const bool gross = in(frame, 15, 17) || frame == 34 || in(frame, 54, 55) || in(frame, 70, 72);
    const std::size_t sliding = gross ? 10 : partial ? 3 : 0;
    const bool moved = frame == 12 || frame == 52 || frame == 69 || frame == 81 || frame == 34;
    for (std::size_t k = 0; k < 12; ++k) {
      ElementTruth& et = gt.fingertips[0].elements[k];
      et.contact = et.visible = true;
      et.fz_n = 0.8;
      et.sliding = k < sliding;
      ElementReading& r = left[k];
      r.contact = true;
      r.has_displacement = frame > 1;
      r.fz = 0.8;
      r.dy_mm = moved && k == 1 ? 10 * cfg.dr_mm : 0.0;
    }
    scorer.add_truth(frame, 0.01 * static_cast<double>(frame), gt, {control::Phase::kTransport, 0},
                     {});
    scorer.add_measurement(0, frame, left, gt.fingertips[0], control::Phase::kTransport, {});
    scorer.add_measurement(1, frame, right, gt.fingertips[1], control::Phase::kTransport, {});
  }
  scorer.finish(false, 1.0, 100);
  const SlipMetrics& m = run.report.slip;
  ASSERT_EQ(m.detector, "paper");
  EXPECT_EQ(m.incipient_episodes, 3U);
  EXPECT_EQ(m.incipient_detected, 2U);
  EXPECT_EQ(m.incipient_lead_frames, 2.0);  // the median of 3, 0 and 2
  // The other detector is scored on the same episodes of the truth.
  EXPECT_EQ(run.report.slip_other.incipient_episodes, 3U);
  EXPECT_LE(run.report.slip_other.incipient_lead_frames, 5.0);  // within a run-up
}

// The least steady grip (docs/rig.md, "The grip's truth"): each frame's is the largest need of
// the frames within 0.1 s before and after it, the window cut at the run's ends.
TEST(GripScoring, SteadyNeedIsTheLargestNeedWithinATenthOfASecond) {
  const struct {
    const char* what;
    std::vector<double> t, need, steady;
  } cases[] = {
      {"real-time spacing", {0.0, 0.04, 0.09, 0.15, 0.30}, {1, 5, 2, 3, 4}, {5, 5, 5, 3, 4}},
      {"a spike at the run's start", {0.0, 0.05, 0.10, 0.15}, {9, 1, 1, 1}, {9, 9, 9, 1}},
      {"a spike at the run's end", {0.0, 0.05, 0.10, 0.15}, {1, 1, 1, 9}, {1, 9, 9, 9}},
      {"frames alone", {0.0, 0.2, 0.4}, {3, 1, 2}, {3, 1, 2}},
      {"one frame", {1.0}, {2}, {2}},
  };
  for (const auto& c : cases) {
    std::vector<double> steady(c.t.size(), -1);
    steady_need(c.t, c.need, kSteadyGripHalfWindowS, steady);
    EXPECT_EQ(steady, c.steady) << c.what;
  }
  // At 100 fps (t = frame / fps, as the runner counts) a spike reaches exactly ten frames either
  // way, 0.1 s in floating point included.
  std::vector<double> t, need;
  for (int n = 1; n <= 60; ++n) {
    t.push_back(static_cast<double>(n) / 100.0);
    need.push_back(n == 31 ? 5.0 : 1.0);
  }
  std::vector<double> steady(t.size());
  steady_need(t, need, kSteadyGripHalfWindowS, steady);
  for (int n = 1; n <= 60; ++n)
    EXPECT_EQ(steady[n - 1], std::abs(n - 31) <= 10 ? 5.0 : 1.0) << n;
}

GripTruth grip_at(double need, std::array<double, kFingertips> applied, bool held,
                  double slide_mm = 0) {
  GripTruth g;
  g.needed_n = need;
  g.applied_n = applied;
  g.held = held;
  g.slide_mm = slide_mm;
  return g;
}

// The ratios over the held frames only, the smaller fingertip's grip over the least steady grip
// (frames 0.2 s apart: each its own window) and the instant's.
TEST(GripScoring, RatiosArePercentilesOverTheHeldFrames) {
  GripScorer s;
  s.reserve(6);
  s.add(0.0, grip_at(1, {2, 3}, false));
  s.add(0.2, grip_at(1, {3, 3}, true));    // 3
  s.add(0.4, grip_at(2, {4, 5}, true));    // 2
  s.add(0.6, grip_at(1, {1.5, 1}, true));  // 1
  s.add(0.8, grip_at(4, {8, 8}, true));    // 2
  s.add(1.0, grip_at(0.1, {9, 9}, false));
  const GripMetrics m = s.finish();
  EXPECT_EQ(m.held_frames, 4U);
  EXPECT_EQ(m.ratio_p50, 2.0);
  EXPECT_EQ(m.ratio_p95, 3.0);
  EXPECT_EQ(m.ratio_max, 3.0);
  EXPECT_EQ(m.instant_ratio_p50, 2.0);
  EXPECT_EQ(m.applied_p50_N, 3.0);
  EXPECT_EQ(m.steady_need_max_N, 4.0);
  // A need that peaks for one frame raises the steady need of its neighbours: the held grip of 4
  // is 4 times the instant need but only once the steady one near the peak.
  GripScorer v;
  const std::vector<double> need{1, 1, 4, 1, 1, 1, 1};
  for (std::size_t k = 0; k < need.size(); ++k)
    v.add(0.05 * static_cast<double>(k), grip_at(need[k], {4, 4}, true));
  const GripMetrics n = v.finish();
  EXPECT_EQ(n.ratio_p50, 1.0);  // five frames of 7 within 0.1 s of the peak
  EXPECT_EQ(n.ratio_max, 4.0);
  EXPECT_EQ(n.instant_ratio_p50, 4.0);
  EXPECT_EQ(n.instant_ratio_p95, 4.0);
  // Nothing held: no ratio.
  GripScorer none;
  none.add(0.0, grip_at(1, {0, 0}, false));
  EXPECT_EQ(none.finish().held_frames, 0U);
}

// The cap's slide: the frames' slides summed over the held frames only.
TEST(GripScoring, SlideAddsUpOverTheHeldFrames) {
  GripScorer s;
  s.add(0.00, grip_at(1, {2, 2}, true, 0.25));
  s.add(0.01, grip_at(1, {2, 2}, true, 0.5));
  s.add(0.02, grip_at(1, {2, 2}, false, 8.0));  // falling, or on the table
  s.add(0.03, grip_at(1, {2, 2}, true, 0.0));
  s.add(0.04, grip_at(1, {2, 2}, true, 1.0));
  EXPECT_EQ(s.finish().cap_slide_carry_mm, 1.75);
}

// The report's recompressions_by_stage: each re-compression under the phase it came in, summing to
// the report's count.
TEST(GripScoring, RecompressionsAreCountedByStage) {
  const LockstepResult a = score_as_lockstep(synthetic_stream(400), control::Config{});
  const auto& by = a.report.recompressions_by_phase;
  EXPECT_EQ(by[static_cast<std::size_t>(control::Phase::kLift)], 1);
  EXPECT_EQ(by[static_cast<std::size_t>(control::Phase::kTransport)], 1);
  EXPECT_EQ(std::accumulate(by.begin(), by.end(), 0), a.report.recompressions);
  const nlohmann::json j = nlohmann::json::parse(report_json(a.report));
  EXPECT_EQ(j.at("recompressions_by_stage"), (nlohmann::json{{"LIFT", 1}, {"TRANSPORT", 1}}));
  // The stream has no grip's truth: nothing held, the ratios null.
  EXPECT_EQ(j.at("grip").at("held_frames"), 0);
  EXPECT_TRUE(j.at("grip").at("ratio_p50").is_null());
}

// Fig. 10's x is the apex's position along the transport, from the cap's place to the bottle.
TEST(Scoring, FigTenXIsAlongTheTransport) {
  WorldParams w;
  w.cap.x_m = 0.35;
  w.cap.y_m = -0.10;
  w.bottle.x_m = 0.35;
  w.bottle.y_m = 0.10;
  const Vec3 d = transport_direction(w);
  EXPECT_NEAR(d.x, 0.0, 1e-12);
  EXPECT_NEAR(d.y, 1.0, 1e-12);
  EXPECT_EQ(d.z, 0.0);
}

}  // namespace
}  // namespace tactile::rig
