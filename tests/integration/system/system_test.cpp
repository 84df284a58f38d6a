// The whole system: the rig in real time, sensor_node and hand_node as three real processes
// talking GigE Vision and ZeroMQ, in the private network namespace this test program runs in
// (127.0.0.2 and 127.0.0.3 on lo). The paper's task end to end, and process faults.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <thread>

#include "garbage.hpp"
#include "process.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using testing::Process;
using testing::TempDir;

// quick.yaml, or its 30 fps twin when built with the sanitizers (tests/integration/CMakeLists.txt).
const std::string kScenario = TACTILE_SYSTEM_SCENARIO;

// The scenario's frame period (ms): hand_node's staleness limit is three of them.
double frame_period_ms() {
  return 1000.0 / rig::load_scenario(kScenario).camera.fps;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class LoopbackSystem {
 public:
  // `rig_options`: added to the rig's command line; `scenario_options` (overrides of the
  // scenario's keys, such as --grip) also to the one that writes the nodes' configurations.
  explicit LoopbackSystem(const std::string& scenario, std::vector<std::string> rig_options = {},
                          const std::vector<std::string>& scenario_options = {})
      : scenario_(scenario) {
    std::vector<std::string> write{TACTILE_RIG_PATH, "--scenario", scenario, "--write-configs",
                                   config().string()};
    write.insert(write.end(), scenario_options.begin(), scenario_options.end());
    const auto r = testing::run(write);
    if (r.exit_code != 0) throw std::runtime_error("rig --write-configs failed: " + r.err);
    std::vector<std::string> rig{TACTILE_RIG_PATH,
                                 "--scenario",
                                 scenario,
                                 "--report",
                                 (dir_ / "report.json").string(),
                                 "--plots",
                                 (dir_ / "plots").string()};
    rig.insert(rig.end(), rig_options.begin(), rig_options.end());
    rig.insert(rig.end(), scenario_options.begin(), scenario_options.end());
    rig_.emplace(std::move(rig));
    start_sensor();
    start_hand();
  }
  ~LoopbackSystem() {
    for (auto* p : {&hand_, &sensor_, &rig_}) {
      if (*p) (*p)->signal(SIGKILL);
    }
  }

  std::filesystem::path config() const { return dir_ / "config"; }
  void start_sensor() {
    sensor_.emplace(std::vector<std::string>{TACTILE_SENSOR_NODE_PATH, "--config",
                                             (config() / "sensor_node.yaml").string()});
  }
  void start_hand() {
    hand_.emplace(std::vector<std::string>{TACTILE_HAND_NODE_PATH, "--config",
                                           (config() / "hand_node.yaml").string()});
  }
  Process& sensor() { return *sensor_; }
  Process& hand() { return *hand_; }
  Process& rig() { return *rig_; }

  // Waits for hand_node's next event of this kind (and phase, when given).
  std::optional<v1::Event> wait_event(v1::EventKind kind, std::chrono::seconds timeout,
                                      const std::string& phase = "") {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    wire::TopicMessage m;
    v1::Envelope env;
    while (std::chrono::steady_clock::now() < deadline) {
      if (!events_.receive(m, 100ms)) continue;
      if (wire::decode(m.payload, env) != wire::DecodeStatus::kOk || !env.has_event()) continue;
      if (env.event().kind() == kind && (phase.empty() || env.event().phase() == phase))
        return env.event();
    }
    return std::nullopt;
  }

  // The cap's position (m) in the first ground truth published at or after at_ns (the rig's
  // clock, CLOCK_REALTIME as the events'), and that truth's time. The subscriber has queued the
  // truth since the start: what is older is read past, so the answer does not depend on how far
  // behind this reader is or on the frame rate.
  struct CapAt {
    std::int64_t time_ns = 0;
    std::array<double, 3> position_m{};
  };
  std::optional<CapAt> cap_position_at(std::int64_t at_ns, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    wire::TopicMessage m;
    v1::Envelope env;
    while (std::chrono::steady_clock::now() < deadline) {
      if (!truth_.receive(m, 20ms)) continue;
      if (wire::decode(m.payload, env) != wire::DecodeStatus::kOk || !env.has_ground_truth())
        continue;
      const auto& t = env.ground_truth();
      if (t.time_ns() < at_ns) continue;
      const auto& p = t.object_position_m();
      return CapAt{t.time_ns(), {p.x(), p.y(), p.z()}};
    }
    return std::nullopt;
  }

  // How far the cap moved in the horizontal plane (mm) over half a second of ground truth that
  // starts 200 ms after held_ns, when the arm was held (it brakes at 2 m/s^2: at rest within
  // 20 ms of the command).
  std::optional<double> cap_moved_while_held(std::int64_t held_ns) {
    const auto before = cap_position_at(held_ns + 200'000'000, 5s);
    if (!before) return std::nullopt;
    const auto after = cap_position_at(before->time_ns + 500'000'000, 5s);
    if (!after) return std::nullopt;
    const auto& b = before->position_m;
    const auto& a = after->position_m;
    return 1000 * std::hypot(a[0] - b[0], a[1] - b[1]);
  }

  // Waits for the rig and hand_node to end, stops sensor_node, and reads the report. The rig
  // ends the scenario (done, dropped, out of time) and hand_node its task just before; when
  // the rig ended first (a drop), hand_node holds for ever on stale data and is given 20 s.
  json finish(std::chrono::seconds timeout) {
    rig_result_ = rig_->wait(timeout);
    hand_result_ = hand_->wait(20s);
    sensor_->signal(SIGINT);
    sensor_result_ = sensor_->wait(20s);
    const std::string report = slurp(dir_ / "report.json");
    return report.empty() ? json() : json::parse(report);
  }
  const testing::ProcessResult& hand_result() const { return hand_result_; }
  const testing::ProcessResult& rig_result() const { return rig_result_; }
  const testing::ProcessResult& sensor_result() const { return sensor_result_; }
  const std::filesystem::path& dir() const { return dir_.path(); }

 private:
  std::string scenario_;
  TempDir dir_;
  zmq::context_t ctx_;
  wire::Subscriber events_{ctx_, {"tcp://127.0.0.1:5558"}, {wire::kEventTopic}};
  wire::Subscriber truth_{ctx_, {"tcp://127.0.0.1:5557"}, {wire::kTruthTopic}};
  std::optional<Process> rig_;
  std::optional<Process> sensor_;
  std::optional<Process> hand_;
  testing::ProcessResult hand_result_;
  testing::ProcessResult rig_result_;
  testing::ProcessResult sensor_result_;
};

// The decisions of a run (its report): a real-time run and a lockstep run of one scenario drive
// one scenario core (rig/lockstep's ScenarioRun), so they must decide these alike.
json decisions(const json& r) {
  json d;
  for (const char* key :
       {"completed", "dropped", "grasp_classified", "release_classified", "tightened_cycle",
        "true_tight_cycle", "case", "negative_case_passed", "opened_in_air"})
    d[key] = r.at(key);
  d["end_reason"] = r.at("lockstep").at("end_reason");
  return d;
}

json lockstep_report(const std::string& scenario, const std::filesystem::path& dir,
                     const std::vector<std::string>& scenario_options = {}) {
  const auto report = dir / "lockstep-report.json";
  std::vector<std::string> argv{TACTILE_RIG_PATH, "--lockstep", "--scenario",
                                scenario,         "--report",   report.string()};
  argv.insert(argv.end(), scenario_options.begin(), scenario_options.end());
  const auto r = testing::run(argv);
  if (r.exit_code != 0) throw std::runtime_error("rig --lockstep failed: " + r.err);
  return json::parse(slurp(report));
}

std::string logs(LoopbackSystem& s) {
  return "\n--- hand_node\n" + s.hand().err_so_far() + "\n--- sensor_node\n" +
         s.sensor().err_so_far() + "\n--- rig\n" + s.rig().err_so_far();
}

TEST(LoopbackSystem, CompletesThePapersTask) {
  LoopbackSystem s(kScenario);
  const json r = s.finish(150s);
  EXPECT_FALSE(s.hand_result().timed_out) << logs(s) << "\n--- report\n" << r.dump();
  EXPECT_EQ(s.hand_result().exit_code, 0) << logs(s);
  EXPECT_EQ(s.rig_result().exit_code, 0) << logs(s);
  EXPECT_EQ(s.sensor_result().exit_code, 0) << logs(s);
  ASSERT_TRUE(r.is_object()) << logs(s);
  EXPECT_EQ(r["completed"], true) << r.dump();
  EXPECT_EQ(r["dropped"], false) << r.dump();
  // The cap's weight slips on lift in only a few frames; a real-time run may miss them (a missed
  // classification only means the lift goes on), but it must never call the lift a release.
  EXPECT_NE(r["grasp_classified"], "release") << r.dump();
  EXPECT_EQ(r["release_classified"], "release") << r.dump();
  EXPECT_EQ(r["over_events"], 0) << r.dump();
  // Tight in the cycle in which the truth says the cap tightened (120 degrees: cycle 2).
  EXPECT_EQ(r["tightened_cycle"], 2) << r.dump();
  EXPECT_EQ(r["true_tight_cycle"], 2) << r.dump();
  // What the system measured was scored against the truth, and commands named their frames.
  // The slip targets (docs/rig.md) are checked in lockstep; in real time on a shared 2-core
  // machine stale holds stop and start the arm and frames come late (precision 0.78 was seen
  // with a build running beside it): the floor here catches a broken measurement or scoring.
  EXPECT_GT(r["slip"]["true_positives"].get<int>(), 0) << r.dump();
  EXPECT_GE(r["slip"]["precision"].get<double>(), 0.7) << r.dump();
  EXPECT_GE(r["slip"]["recall"].get<double>(), 0.7) << r.dump();
  ASSERT_TRUE(r["latency_ms"].is_object()) << r.dump();
  EXPECT_GT(r["latency_ms"]["p50"].get<double>(), 0.0);
  EXPECT_LE(r["latency_ms"]["p50"].get<double>(), r["latency_ms"]["max"].get<double>());
  for (const char* png : {"fig10.png", "timeline.png"}) {
    EXPECT_GT(std::filesystem::file_size(s.dir() / "plots" / png), 1000U) << png;
  }
  EXPECT_EQ(decisions(r), decisions(lockstep_report(kScenario, s.dir()))) << r.dump();
  // Both programs name the controller in their first lines, and the report does: the scenario
  // leaves the detector to the control core's default.
  EXPECT_NE(s.rig_result().err.find("(real time): slip detector: learned, grip: paper\n"),
            std::string::npos)
      << logs(s);
  EXPECT_NE(s.hand_result().err.find("info: slip detector: learned, grip: paper\n"),
            std::string::npos)
      << logs(s);
  EXPECT_EQ(r["controller"], (json{{"slip_detector", "learned"}, {"grip", "paper"}})) << r.dump();
  // The one scorer gives the real-time run the grip's truth too (docs/rig.md, "The grip's truth"):
  // the paper's grip holds the carried cap with more than the least that holds.
  EXPECT_GT(r["grip"]["held_frames"].get<int>(), 0) << r.dump();
  EXPECT_GT(r["grip"]["ratio_p50"].get<double>(), 1.0) << r.dump();
  EXPECT_TRUE(r["recompressions_by_stage"].is_object()) << r.dump();
  // The machine over the run beside the latency (docs/rig.md, "The machine's load"), in the
  // report and in the rig's log on the latency's line.
  ASSERT_TRUE(r["machine"].is_object()) << r.dump();
  EXPECT_GE(r["machine"]["cpu_steal_pct"].get<double>(), 0.0) << r.dump();
  EXPECT_GE(r["machine"]["load_average_1m"].get<double>(), 0.0) << r.dump();
  EXPECT_GT(r["machine"]["cores"].get<int>(), 0) << r.dump();
  EXPECT_TRUE(r["machine"]["explains_latency"].is_boolean()) << r.dump();
  EXPECT_NE(s.rig_result().err.find(" ms; machine: CPU steal "), std::string::npos) << logs(s);
}

// The margin grip (docs/control.md, "The margin grip") run by hand_node over real sockets, as in
// lockstep: the rig's configuration gives hand_node the grip, the task completes without a drop
// or OVER, the report scores the grip against the least that holds (about 5 times it, against
// the paper grip's 25-30 on this scenario), and the run decides as the lockstep run of the same
// file with the same grip.
TEST(LoopbackSystem, TheMarginGripHoldsTheCapOverRealSockets) {
  const std::vector<std::string> margin{"--grip", "margin"};
  LoopbackSystem s(kScenario, {}, margin);
  const json r = s.finish(150s);
  EXPECT_FALSE(s.hand_result().timed_out) << logs(s) << "\n--- report\n" << r.dump();
  EXPECT_EQ(s.hand_result().exit_code, 0) << logs(s);
  EXPECT_EQ(s.rig_result().exit_code, 0) << logs(s);
  ASSERT_TRUE(r.is_object()) << logs(s);
  EXPECT_NE(s.hand_result().err.find("info: slip detector: learned, grip: margin\n"),
            std::string::npos)
      << logs(s);
  EXPECT_EQ(r["controller"], (json{{"slip_detector", "learned"}, {"grip", "margin"}})) << r.dump();
  EXPECT_EQ(r["completed"], true) << r.dump();
  EXPECT_EQ(r["dropped"], false) << r.dump();
  EXPECT_EQ(r["over_events"], 0) << r.dump();
  EXPECT_EQ(r["release_classified"], "release") << r.dump();
  EXPECT_EQ(r["tightened_cycle"], r["true_tight_cycle"]) << r.dump();
  ASSERT_GT(r["grip"]["held_frames"].get<int>(), 0) << r.dump();
  EXPECT_GT(r["grip"]["ratio_p50"].get<double>(), 1.0) << r.dump();
  EXPECT_LT(r["grip"]["ratio_p50"].get<double>(), 12.0) << r.dump();
  // The slide is scored in real time too; its target (1 mm in 95 % of the sweep's scenarios) is
  // the sweep's, not one run's: under the sanitizers at 30 fps one run slid 3.7 mm (lockstep: 0.3).
  EXPECT_GE(r["grip"]["cap_slide_carry_mm"].get<double>(), 0.0) << r.dump();
  EXPECT_EQ(decisions(r), decisions(lockstep_report(kScenario, s.dir(), margin))) << r.dump();
}

// The sweep's negative case in real time: the bottle stands away from where the controller
// looks for it, the cap lowered there meets nothing. No release may be classified and the
// fingers may not open in the air (opened_in_air, which the real-time run once never set), and
// the run ends as the lockstep run of the same file does: the task aborted at lower_limit_m.
TEST(LoopbackSystem, DisplacedBottleDecidesAsTheLockstepRunDoes) {
  LoopbackSystem s(TACTILE_DISPLACED_SCENARIO);
  const json r = s.finish(150s);
  ASSERT_TRUE(r.is_object()) << logs(s);
  EXPECT_EQ(s.rig_result().exit_code, 0) << logs(s);
  EXPECT_EQ(r["case"], "bottle_displaced") << r.dump();
  EXPECT_EQ(r["release_classified"], nullptr) << r.dump();
  EXPECT_EQ(r["opened_in_air"], false) << r.dump();
  EXPECT_EQ(r["negative_case_passed"], true) << r.dump();
  EXPECT_EQ(decisions(r), decisions(lockstep_report(TACTILE_DISPLACED_SCENARIO, s.dir())))
      << r.dump();
}

// A user's join of a recording: every TactileFrame finds the GroundTruth of its image by the
// camera's block id (sensor_id, camera_frame_id; or a resent image's id), and that is the truth
// the camera timestamp finds too. A few seconds of the running system, read as a recorder would.
TEST(LoopbackSystem, GroundTruthJoinsItsFramesByBlockId) {
  zmq::context_t ctx;
  wire::Subscriber frames(ctx, {"tcp://127.0.0.1:5555"}, {wire::kFrameTopicPrefix});
  wire::Subscriber truth(ctx, {"tcp://127.0.0.1:5557"}, {wire::kTruthTopic});
  // Every 10th frame left unrendered on purpose: both cameras send the image before it again, so
  // the truth's resend path (resent_camera_frame_ids) runs on every run, not only when the
  // machine makes the rig late.
  LoopbackSystem s(kScenario, {"--late-every", "10"});
  std::vector<v1::TactileFrame> got_frames;
  std::vector<v1::GroundTruth> got_truth;
  wire::TopicMessage m;
  v1::Envelope env;
  const auto read_truth = [&] {
    while (truth.receive(m, 0ms)) {
      ASSERT_EQ(wire::decode(m.payload, env), wire::DecodeStatus::kOk);
      ASSERT_TRUE(env.has_ground_truth());
      got_truth.push_back(env.ground_truth());
    }
  };
  // Frames from the first truth this subscriber got on: truth is published in frame order, so
  // every truth of a later frame reaches it (it subscribed late to the earlier ones).
  std::int64_t from_ns = 0;
  std::optional<std::chrono::steady_clock::time_point> until;
  const auto give_up = std::chrono::steady_clock::now() + 60s;
  while (!until || std::chrono::steady_clock::now() < *until) {
    ASSERT_LT(std::chrono::steady_clock::now(), give_up) << "no frames and truth" << logs(s);
    read_truth();
    if (from_ns == 0 && !got_truth.empty()) {
      from_ns = got_truth.front().fingertips(0).camera_timestamp_ns();
      until = std::chrono::steady_clock::now() + 3s;
    }
    if (!frames.receive(m, 20ms)) continue;
    ASSERT_EQ(wire::decode(m.payload, env), wire::DecodeStatus::kOk);
    if (from_ns != 0 && env.tactile_frame().camera_timestamp_ns() >= from_ns)
      got_frames.push_back(env.tactile_frame());
  }
  // The truth of the last frames is published once the cameras sent newer images (or at most
  // four periods later).
  const auto truth_until = std::chrono::steady_clock::now() + 1s;
  while (std::chrono::steady_clock::now() < truth_until) {
    read_truth();
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(got_frames.size(), 50U) << logs(s);

  std::size_t resent = 0;
  std::size_t wraps = 0;  // a block id below its sensor's previous one: 65535 to 1
  std::map<std::string, std::uint64_t> last_id;
  for (const v1::TactileFrame& f : got_frames) {
    auto& last = last_id[f.sensor_id()];
    if (f.camera_frame_id() < last) ++wraps;
    last = f.camera_frame_id();
    std::vector<std::size_t> by_id, by_time;
    for (std::size_t k = 0; k < got_truth.size(); ++k) {
      for (const v1::FingertipTruth& t : got_truth[k].fingertips()) {
        if (t.sensor_id() != f.sensor_id()) continue;
        const auto& again = t.resent_camera_frame_ids();
        const bool is_resend =
            std::find(again.begin(), again.end(), f.camera_frame_id()) != again.end();
        if (t.camera_frame_id() == f.camera_frame_id() || is_resend) by_id.push_back(k);
        if (is_resend) ++resent;
        if (t.camera_timestamp_ns() == f.camera_timestamp_ns()) by_time.push_back(k);
      }
    }
    ASSERT_EQ(by_id.size(), 1U) << f.sensor_id() << " frame " << f.sequence() << " block id "
                                << f.camera_frame_id() << ": truths with that id " << by_id.size();
    ASSERT_EQ(by_time.size(), 1U) << f.sensor_id() << " frame " << f.sequence();
    EXPECT_EQ(by_id[0], by_time[0])
        << f.sensor_id() << " frame " << f.sequence() << " block id " << f.camera_frame_id();
  }
  // About one frame in ten is a resent image (sensor_node measures it again); each joined the
  // truth of the image it repeats, by its resent id, and that truth is the one its timestamp finds.
  EXPECT_GE(resent, got_frames.size() / 20) << logs(s);
  std::fprintf(
      stderr,
      "[measured] %zu TactileFrames joined their GroundTruth by block id (%zu of them a "
      "resent image), the same truth as by camera timestamp; %zu truths; %zu block id wraps\n",
      got_frames.size(), resent, got_truth.size(), wraps);
}

TEST(ProcessFaults, SensorNodeKilledInTransportHoldsThenResumesFromItsSavedReference) {
  LoopbackSystem s(kScenario);
  ASSERT_TRUE(s.wait_event(v1::EVENT_KIND_PHASE, 60s, "TRANSPORT")) << logs(s);
  ASSERT_NE(s.sensor().err_so_far().find("reference saved"), std::string::npos) << logs(s);
  s.sensor().signal(SIGKILL);
  const auto stale = s.wait_event(v1::EVENT_KIND_STALE_HOLD, 5s);
  ASSERT_TRUE(stale) << logs(s);
  // The hold came within three frame periods of the data going stale: the event names the
  // last frames hand_node had; stale_after_s is 3 periods (30 ms at 100 fps), and 10 ms of
  // scheduling is allowed.
  std::int64_t last_frame_ns = 0;
  for (const auto& a : stale->answers())
    last_frame_ns = std::max(last_frame_ns, a.camera_timestamp_ns());
  ASSERT_GT(last_frame_ns, 0);
  const double waited_ms = static_cast<double>(stale->time_ns() - last_frame_ns) * 1e-6;
  const double period_ms = frame_period_ms();
  // Built with the sanitizers (30 fps, programs two to three times slower) on a shared machine,
  // hand_node's wake-ups come late by more than a period at times (293 ms was seen against 210):
  // six more periods there. The promise itself is checked by the Release build.
  const double sanitizer_periods = TACTILE_SANITIZED ? 6.0 : 0.0;
  EXPECT_LE(waited_ms, 3 * period_ms + 3 * period_ms + sanitizer_periods * period_ms + 10.0)
      << "STALE_HOLD " << waited_ms << " ms after the last frame";
  // While held, the cap (in the hand, mid-transport) does not move.
  const auto moved = s.cap_moved_while_held(stale->time_ns());
  ASSERT_TRUE(moved) << logs(s);
  EXPECT_LT(*moved, 1.0) << "the cap moved " << *moved << " mm while the data was stale";
  std::fprintf(stderr,
               "[measured] STALE_HOLD %.1f ms after the last frame; cap moved %.3f mm held\n",
               waited_ms, *moved);
  // sensor_node comes back, loads the reference it saved instead of capturing one under load,
  // and the task carries on to the end.
  s.start_sensor();
  EXPECT_TRUE(s.wait_event(v1::EVENT_KIND_RESUMED, 30s)) << logs(s);
  const json r = s.finish(150s);
  EXPECT_NE(s.sensor_result().err.find("reference loaded from"), std::string::npos)
      << s.sensor_result().err;
  EXPECT_EQ(s.sensor_result().err.find("capturing the no-load reference"), std::string::npos);
  EXPECT_EQ(r["completed"], true) << r.dump() << logs(s);
  EXPECT_EQ(r["dropped"], false) << r.dump();
}

TEST(ProcessFaults, ArmEndpointFloodedWithGarbageTheTaskGoesOnAndEveryMessageIsRefused) {
  LoopbackSystem s(kScenario);
  ASSERT_TRUE(s.wait_event(v1::EVENT_KIND_PHASE, 60s)) << logs(s);
  // A second client on the arm controller's endpoint sends 100 000 mutated heartbeats (and
  // what decodes of them is a stranger's heartbeat): none may move the arm, take the link
  // from hand_node or keep its deadman from tripping.
  std::string valid;
  {
    v1::Envelope e;
    e.mutable_heartbeat()->set_time_ns(1);
    wire::encode(e, valid);
  }
  constexpr std::uint64_t kMessages = 100'000;
  std::uint64_t sent = 0;
  std::thread flood([&] {
    zmq::context_t ctx;
    zmq::socket_t dealer(ctx, zmq::socket_type::dealer);
    // What is still queued when the flood ends (up to the send HWM of 1000 and what the kernel
    // buffers) reaches the rig only as fast as it reads: built with the sanitizers on a loaded
    // machine that took longer than the 2 s linger this socket had, and 1193 messages were
    // dropped unsent (refused 98807 of 100000, issue 39). The rig reads all of it long before the
    // task ends; 60 s bounds the wait.
    dealer.set(zmq::sockopt::linger, 60000);
    dealer.set(zmq::sockopt::sndtimeo, 2000);
    dealer.connect("tcp://127.0.0.1:5556");
    testing::Garbage g(valid, 23);
    for (std::uint64_t i = 0; i < kMessages; ++i) {
      const std::string m = g.next();
      if (!dealer.send(zmq::buffer(m), zmq::send_flags::none)) break;
      ++sent;
      if (i % 1000 == 999) std::this_thread::sleep_for(5ms);  // spread over the run
    }
  });
  const json r = s.finish(150s);
  flood.join();
  EXPECT_FALSE(s.hand_result().timed_out) << logs(s) << "\n--- report\n" << r.dump();
  EXPECT_EQ(sent, kMessages);
  EXPECT_EQ(s.hand_result().exit_code, 0) << logs(s);
  EXPECT_EQ(s.rig_result().exit_code, 0) << s.rig_result().err;
  EXPECT_EQ(r["completed"], true) << r.dump();
  EXPECT_EQ(r["dropped"], false) << r.dump();
  // (OVER may come: the flood and its sender load the two cores, frames come late and a
  // re-compression can overshoot F2, which the estimator then backs off from.)
  // The rig counts what it refused; hand_node's own words are never refused, so all of the
  // flood is there (a mutation that happens to be a valid ArmCommand would be followed: that
  // is what CURVE on the arm link is for, docs/security.md).
  const std::regex refused("commands ([0-9]+) \\(refused ([0-9]+)\\)");
  std::smatch m;
  const std::string& log = s.rig_result().err;
  ASSERT_TRUE(std::regex_search(log, m, refused)) << log;
  EXPECT_GT(std::stoull(m[1].str()), 0U);
  EXPECT_GE(std::stoull(m[2].str()), kMessages - 10) << m[0];
  EXPECT_LE(std::stoull(m[2].str()), kMessages) << m[0];
  EXPECT_EQ(log.find("commands now come from another client"), std::string::npos) << log;
  std::fprintf(stderr, "[measured] sent %llu, rig: %s\n", static_cast<unsigned long long>(sent),
               m[0].str().c_str());
}

// Issue 39, item 7: the flooded-arm run that once ended "segment timed out" in LOWER under the
// sanitizers, reproduced on purpose. What the flood and the sanitizers did there was to leave
// hand_node unscheduled past the arm controller's deadman (40 ms) during a motion; here hand_node
// is stopped (SIGSTOP) for 45 to 75 ms every 0.7 s from the carry to the release: just past the
// deadman, so that it wakes within a state period of the trip. Each stop trips the deadman
// mid-MoveTo; hand_node, running again, answers the ArmState that reports the hold by sending the
// motion again. 55d5f03 closed a window in which a command sent on waking ended the hold before
// any ArmState had reported it, so the motion was never sent again and the segment timed out:
// what this test found of that window is in docs/reliability.md ("The flooded arm").
TEST(ProcessFaults, HandNodeStalledPastTheDeadmanDuringTheMotionsTheArmResumesEachTime) {
  LoopbackSystem s(kScenario);
  ASSERT_TRUE(s.wait_event(v1::EVENT_KIND_PHASE, 60s, "TRANSPORT")) << logs(s);
  std::atomic<bool> stalling{true};
  int stalls = 0;
  std::thread staller([&] {
    // Bounded: 120 stalls are well over a minute, longer than the carry and the lowering.
    while (stalling.load() && stalls < 120) {
      s.hand().signal(SIGSTOP);
      std::this_thread::sleep_for(std::chrono::milliseconds(45 + 5 * (stalls % 7)));
      s.hand().signal(SIGCONT);
      ++stalls;
      // Each hold defers the lowering's release decision by resume_settle_s (0.3 s) and three
      // fresh frames (0.1 s at the sanitizers' 30 fps): stalls closer than that keep deferring
      // it while the arm goes on down, and the fingers slide past the cap (docs/reliability.md).
      std::this_thread::sleep_for(650ms);
    }
  });
  const bool released = s.wait_event(v1::EVENT_KIND_RELEASE_CLASSIFIED, 90s).has_value();
  stalling = false;
  staller.join();
  const json r = s.finish(150s);
  ASSERT_TRUE(released) << logs(s) << "\n--- report\n" << r.dump();
  EXPECT_FALSE(s.hand_result().timed_out) << logs(s);
  EXPECT_EQ(s.hand_result().err.find("segment timed out"), std::string::npos) << logs(s);
  EXPECT_EQ(r["completed"], true) << r.dump() << logs(s);
  EXPECT_EQ(r["dropped"], false) << r.dump();
  // The stalls did trip the deadman (the rig's exit line counts its trips), more than once.
  const std::regex trips("deadman trips ([0-9]+)");
  std::smatch m;
  const std::string& log = s.rig_result().err;
  ASSERT_TRUE(std::regex_search(log, m, trips)) << log;
  const unsigned long held = std::stoul(m[1].str());
  EXPECT_GE(held, 2U) << "the stalls never held the arm: " << m[0];
  EXPECT_NE(s.hand_result().err.find("the arm controller's deadman held the arm: resuming"),
            std::string::npos)
      << s.hand_result().err;
  std::fprintf(stderr, "[measured] %d stalls of 45-75 ms, %lu deadman holds, completed\n", stalls,
               held);
}

TEST(ProcessFaults, HandNodeKilledTheDeadmanHoldsTheArmWithin50ms) {
  LoopbackSystem s(kScenario);
  ASSERT_TRUE(s.wait_event(v1::EVENT_KIND_PHASE, 60s, "TRANSPORT")) << logs(s);
  s.hand().signal(SIGKILL);
  // The rig says how long it had heard nothing when its deadman held the arm.
  const std::regex held("deadman: nothing from hand_node for ([0-9]+) ms: arm held");
  std::smatch m;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  std::string log;
  while (std::chrono::steady_clock::now() < deadline) {
    log = s.rig().err_so_far();
    if (std::regex_search(log, m, held)) break;
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_FALSE(m.empty()) << log;
  EXPECT_LE(std::stoi(m[1].str()), 50) << m[0];
  std::fprintf(stderr, "[measured] %s\n", m[0].str().c_str());
  // And the arm stays held: the cap stops where it is.
  const auto moved = s.cap_moved_while_held(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                std::chrono::system_clock::now().time_since_epoch())
                                                .count());
  ASSERT_TRUE(moved) << log;
  EXPECT_LT(*moved, 1.0);
  std::fprintf(stderr, "[measured] cap moved %.3f mm while the deadman held\n", *moved);
  s.rig().signal(SIGINT);
  const auto rig = s.rig().wait(30s);
  EXPECT_EQ(rig.exit_code, 0) << rig.err;
}

}  // namespace
}  // namespace tactile
