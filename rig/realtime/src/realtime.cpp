#include "tactile/rig/realtime.hpp"

#include <fmt/format.h>
#include <sys/timerfd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <thread>

#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/control/config.hpp"
#include "tactile/rig/arm_link.hpp"
#include "tactile/rig/optics.hpp"
#include "tactile/rig/scoring.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/rig/truth.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/fd.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::rig {
namespace {

using std::chrono::milliseconds;

void fill_truth_message(const GroundTruth& gt, std::int64_t now_ns, v1::GroundTruth& out) {
  static const char* kIds[kFingertips] = {"left", "right"};
  out.set_time_ns(now_ns);
  out.set_sim_time_s(gt.sim_time_s);
  auto* tips = out.mutable_fingertips();
  while (tips->size() < static_cast<int>(kFingertips))
    tips->Add();
  for (std::size_t i = 0; i < kFingertips; ++i) {
    v1::FingertipTruth& t = (*tips)[static_cast<int>(i)];
    const FingertipTruth& ft = gt.fingertips[i];
    t.set_sensor_id(kIds[i]);
    t.set_camera_frame_id(ft.camera_frame_id);
    t.set_camera_timestamp_ns(ft.camera_timestamp_ns);
    auto* els = t.mutable_elements();
    while (els->size() < static_cast<int>(kElementsPerFingertip))
      els->Add();
    for (std::size_t k = 0; k < kElementsPerFingertip; ++k) {
      const ElementTruth& et = ft.elements[k];
      v1::ElementTruth& e = (*els)[static_cast<int>(k)];
      e.set_id(et.id);
      e.set_fz_n(et.fz_n);
      e.set_fx_n(et.fx_n);
      e.set_fy_n(et.fy_n);
      e.set_sliding(et.sliding);
      e.set_ux_mm(et.ux_mm);
      e.set_uy_mm(et.uy_mm);
    }
  }
  out.mutable_object_position_m()->set_x(gt.object_position_m.x);
  out.mutable_object_position_m()->set_y(gt.object_position_m.y);
  out.mutable_object_position_m()->set_z(gt.object_position_m.z);
  out.set_cap_angle_deg(gt.cap_angle_deg);
  out.set_cap_tight(gt.cap_tight);
  out.set_dropped(gt.dropped);
  out.set_cap_on_bottle(gt.cap_on_bottle);
  out.set_twist_cycle(gt.twist_cycle);
}

// A timerfd on CLOCK_REALTIME (util::realtime_ns's clock), armed for one absolute instant: a
// file descriptor that becomes readable then, for poll. Without one (no timerfd) fd() is -1
// and the millisecond timeout alone bounds the wait.
class WakeTimer {
 public:
  WakeTimer() : fd_(::timerfd_create(CLOCK_REALTIME, TFD_NONBLOCK | TFD_CLOEXEC)) {
    if (fd_.get() < 0)
      util::log_warn("no timerfd ({}): frames start up to a millisecond late",
                     std::strerror(errno));
  }
  int fd() const { return fd_.get(); }
  // Re-arming clears an expiry not yet read, so the descriptor is readable only from `at_ns` on.
  void arm_at(std::int64_t at_ns) const {
    if (fd_.get() < 0) return;
    itimerspec when{};
    when.it_value.tv_sec = static_cast<time_t>(at_ns / 1'000'000'000);
    when.it_value.tv_nsec = static_cast<long>(at_ns % 1'000'000'000);
    ::timerfd_settime(fd_.get(), TFD_TIMER_ABSTIME, &when, nullptr);
  }

 private:
  util::Fd fd_;
};

// A truth kept until the measured frames of its instant arrive (a few frame periods).
struct KeptTruth {
  std::uint64_t frame = 0;
  double t = 0;
  control::Phase phase = control::Phase::kIdle;  // the controller's, when it was taken
  GroundTruth truth;
  std::array<bool, kFingertips> scored{};
};

}  // namespace

RealtimeResult run_realtime(const Scenario& sc, const RealtimeOptions& opt) {
  RealtimeResult result;
  LockstepResult& run = result.run;
  const control::Config cfg = scenario_controller_config(sc);
  World world(sc.world);
  const double dt = sc.step_s();
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / sc.camera.fps));
  const auto lead_ns =
      std::min(static_cast<std::int64_t>(opt.render_lead_s * 1e9), period_ns * 3 / 4);

  // Sensors: calibrations (written for sensor_node and hand_node), renderers, cameras.
  const auto normals = world.element_normals();
  const auto& ids = kFingertipIds;
  std::vector<std::unique_ptr<camera::FakeGvCamera>> cameras;
  CameraParams cam = sc.camera;
  cam.refresh_outside_disks = opt.full_noise;
  SimulatedSensors sensors(sc, cam, normals);
  run.calibrations = sensors.calibrations();
  for (std::size_t i = 0; i < kFingertips; ++i) {
    if (!opt.calibration_dir.empty()) {
      config::save_calibration(opt.calibration_dir / (std::string(ids[i]) + ".yaml"),
                               run.calibrations[i]);
    }
    camera::FakeGvCameraOptions fo;
    fo.address = opt.camera_addresses[i];
    fo.serial = opt.camera_serials[i];
    fo.width = cam.width;
    fo.height = cam.height;
    fo.pixel_format = cam.bit_depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
    fo.frame_rate_hz = cam.fps;
    cameras.push_back(std::make_unique<camera::FakeGvCamera>(fo));
    util::log_info("camera {} ({}) serving on {}", ids[i], fo.serial, fo.address);
  }
  RunScorer scorer(run, cfg, opt.record_series);
  const Vec3 transport = transport_direction(sc.world);

  // Sockets.
  zmq::context_t ctx;
  wire::Router arm(ctx, opt.arm_endpoint, opt.arm_security ? &*opt.arm_security : nullptr);
  std::optional<wire::Publisher> truth_pub;
  if (!opt.truth_endpoint.empty()) truth_pub.emplace(ctx, opt.truth_endpoint);
  wire::Subscriber frames(ctx, opt.observe_frames, {wire::kFrameTopicPrefix},
                          opt.observe_security ? &*opt.observe_security : nullptr);
  std::optional<wire::Subscriber> events;
  if (!opt.observe_events.empty())
    events.emplace(ctx, std::vector<std::string>{opt.observe_events},
                   std::vector<std::string>{wire::kEventTopic});
  util::log_info("arm controller on {}, ground truth on {}, deadman {:.0f} ms", arm.endpoint(),
                 truth_pub ? truth_pub->endpoint() : std::string("(none)"), opt.deadman_s * 1e3);
  if (opt.on_ready) opt.on_ready();

  // Reused buffers.
  std::string peer;  // the client the arm answers
  std::string from;  // the sender of the message at hand
  bool have_peer = false;
  std::vector<std::uint8_t> payload;
  wire::TopicMessage msg;
  wire::EnvelopeDecoder decoder;
  v1::Envelope truth_env;
  v1::Envelope state_env;
  std::string out;
  wire::ReceivedCommand cmd;
  const wire::FingertipIds wire_ids{"left", "right"};
  std::array<wire::ReceivedFrame, kFingertips> measured;
  for (std::size_t i = 0; i < kFingertips; ++i)
    measured[i].elements.resize(kElementsPerFingertip);
  std::deque<KeptTruth> kept;
  std::vector<double> latencies_ms;
  latencies_ms.reserve(1 << 16);
  RealtimeCounters& c = result.counters;

  const std::int64_t start_ns = util::realtime_ns();
  std::int64_t last_heard_ns = 0;
  bool deadman_tripped = false;
  std::uint64_t last_command = 0;
  control::Phase phase = control::Phase::kIdle;
  std::uint32_t twist_cycle = 0;
  bool ended = false;
  std::int64_t ended_at_ns = 0;
  std::int64_t dropped_at_ns = -1;
  std::uint64_t frame = static_cast<std::uint64_t>((start_ns + lead_ns) / period_ns) + 1;
  const std::uint64_t first_frame = frame;
  Report& rep = run.report;
  rep.end_reason = "max_time";

  // Steps the world until its clock reaches the wall-clock instant `t_ns`.
  const auto advance_to = [&](std::int64_t t_ns) {
    const double target = static_cast<double>(t_ns - start_ns) * 1e-9;
    while (world.time() + 0.5 * dt < target) {
      if (!world.step(dt)) {
        run.physics_finite = false;
        break;
      }
    }
  };

  // The peer the arm answers: the first client that spoke (a heartbeat) or the last that sent a
  // valid command. Garbage never changes it, and only its words keep the deadman from tripping.
  const auto on_arm_message = [&](std::int64_t now_ns) {
    const auto st = decoder.decode(payload);
    const v1::Envelope& env = decoder.envelope();
    if (st != wire::DecodeStatus::kOk) {
      ++c.invalid_commands;
      return;
    }
    if (env.has_heartbeat()) {
      if (!have_peer) {
        util::log_info("hand_node connected");
      } else if (from != peer && deadman_tripped) {
        // The old client fell silent and the arm is held: a new one (a restarted hand_node)
        // takes over.
        util::log_info("a new client takes over after the deadman hold");
      } else if (from != peer) {
        ++c.invalid_commands;  // another client's heartbeat while ours is alive: refused
        return;
      }
      peer = from;
      have_peer = true;
      last_heard_ns = now_ns;
      return;
    }
    if (!env.has_arm_command() ||
        wire::read_arm_command(env.arm_command(), wire_ids, cmd) != wire::DecodeStatus::kOk) {
      ++c.invalid_commands;
      return;
    }
    if (!have_peer) util::log_info("hand_node connected");
    if (have_peer && from != peer) util::log_warn("commands now come from another client");
    peer = from;
    have_peer = true;
    last_heard_ns = now_ns;
    // The deadman hold lasts until hand_node commands again (its ArmStates carry the fault).
    if (deadman_tripped) {
      util::log_info("hand_node commands again after the deadman hold");
      deadman_tripped = false;
    }
    ++c.commands;
    last_command = cmd.sequence;
    for (std::size_t i = 0; i < cmd.answers.count; ++i) {
      const std::int64_t cam_ts = cmd.answers.refs[i].camera_timestamp_ns;
      if (cam_ts <= 0) continue;
      const double ms = static_cast<double>(now_ns - cam_ts) * 1e-6;
      latencies_ms.push_back(ms);
      // Answers older than a period are the tail of latency_ms: say which they were.
      if (now_ns - cam_ts > period_ns) {
        util::log_debug("command {} answered frame {} of fingertip {} {:.2f} ms after its exposure",
                        cmd.sequence, cmd.answers.refs[i].sequence, cmd.answers.refs[i].fingertip,
                        ms);
      }
    }
    advance_to(now_ns);  // the command acts from the moment it arrived
    if (!world.apply(to_world_command(cmd.command))) ++c.invalid_commands;
  };

  // Holds the arm once hand_node has been silent longer than the deadman. Checked whenever the
  // sockets are served (at most 5 ms apart), not only once per frame: at 30 fps a check per
  // frame would hold the arm up to a period late.
  const auto check_deadman = [&](std::int64_t now_ns) {
    if (!have_peer || deadman_tripped ||
        now_ns - last_heard_ns <= static_cast<std::int64_t>(opt.deadman_s * 1e9))
      return;
    deadman_tripped = true;
    ++c.deadman_trips;
    advance_to(now_ns);  // the hold acts from the moment it was decided
    world.apply(to_world_command(control::Command::hold()));
    util::log_warn("deadman: nothing from hand_node for {:.0f} ms: arm held",
                   static_cast<double>(now_ns - last_heard_ns) * 1e-6);
  };

  const auto on_frame = [&]() {
    if (decoder.decode(msg.payload) != wire::DecodeStatus::kOk) return;
    const v1::Envelope& env = decoder.envelope();
    if (!env.has_tactile_frame()) return;
    const v1::TactileFrame& f = env.tactile_frame();
    const std::size_t tip = f.sensor_id() == "left"    ? 0
                            : f.sensor_id() == "right" ? 1
                                                       : kFingertips;
    if (tip == kFingertips) return;
    if (f.status() != v1::FRAME_STATUS_COMPLETE) {
      if (f.status() != v1::FRAME_STATUS_NO_REFERENCE) ++c.frames_incomplete;
      return;
    }
    if (wire::read_tactile_frame(f, run.calibrations[tip], measured[tip]) !=
        wire::DecodeStatus::kOk)
      return;
    const auto it = std::find_if(kept.begin(), kept.end(), [&](const KeptTruth& k) {
      return k.truth.fingertips[tip].camera_timestamp_ns == f.camera_timestamp_ns();
    });
    if (it == kept.end() || it->scored[tip]) {
      ++c.frames_unmatched;  // an image the camera sent again, or one older than the window
      return;
    }
    it->scored[tip] = true;
    ++c.frames_scored;
    scorer.add_measurement(tip, it->frame - first_frame, measured[tip].elements,
                           it->truth.fingertips[tip], it->phase);
  };

  const auto on_event = [&]() {
    if (decoder.decode(msg.payload) != wire::DecodeStatus::kOk) return;
    const v1::Envelope& env = decoder.envelope();
    if (!env.has_event()) return;
    const v1::Event& e = env.event();
    ++c.events;
    const auto p = wire::phase_from_string(e.phase());
    if (p) phase = *p;
    twist_cycle = std::max(twist_cycle, e.cycle());
    const double t = static_cast<double>(util::realtime_ns() - start_ns) * 1e-9;
    control::Event ce;
    ce.kind = static_cast<control::EventKind>(e.kind());
    ce.phase = p.value_or(phase);
    ce.cycle = e.cycle();
    for (std::size_t i = 0; i < kFingertips; ++i) {
      if (e.sensor_id() == ids[i]) ce.fingertip = static_cast<std::int8_t>(i);
    }
    ce.value = e.value();
    ce.text = e.text().c_str();  // copied by the scorer
    scorer.add_event(ce, t);
    if (e.kind() == v1::EVENT_KIND_DONE || e.kind() == v1::EVENT_KIND_ABORTED) {
      if (!ended) {
        ended = true;
        ended_at_ns = util::realtime_ns();
      }
    }
  };

  std::array<zmq::socket_ref, 3> sockets{arm.socket(), frames.socket(),
                                         events ? events->socket() : frames.socket()};
  // Wakes the serving loop at the instant to render: ZeroMQ's poll counts whole milliseconds, and
  // a timeout rounded up started the frame up to a millisecond late (images then published after
  // their send instant), one rounded down would spin through the last millisecond.
  const WakeTimer render_timer;
  const auto max_ns = static_cast<std::int64_t>(sc.max_time_s * 1e9);
  while (!util::stop_requested()) {
    const std::int64_t send_ns = static_cast<std::int64_t>(frame) * period_ns;
    const std::int64_t render_ns = send_ns - lead_ns;
    // Serve the sockets until it is time to render the next frame.
    for (;;) {
      std::int64_t now = util::realtime_ns();
      const std::int64_t wait_ns = render_ns - now;
      if (wait_ns > 0) {
        render_timer.arm_at(render_ns);
        wire::poll_readable(sockets, milliseconds(std::min<std::int64_t>(wait_ns / 1000000 + 1, 5)),
                            render_timer.fd());
      }
      now = util::realtime_ns();
      while (arm.receive(from, payload, milliseconds(0)))
        on_arm_message(util::realtime_ns());
      while (frames.receive(msg, milliseconds(0)))
        on_frame();
      while (events && events->receive(msg, milliseconds(0)))
        on_event();
      check_deadman(util::realtime_ns());
      if (now >= render_ns || util::stop_requested()) break;
    }
    const std::int64_t now = util::realtime_ns();
    if (now > send_ns) {
      // Too late for this frame: the camera sends the previous image again. Skip to the next.
      ++c.late_renders;
      frame = static_cast<std::uint64_t>((now + lead_ns) / period_ns) + 1;
      continue;
    }

    // The world at the instant the camera sends the frame.
    const std::int64_t started_ns = now;
    advance_to(send_ns);
    const std::int64_t stepped_ns = util::realtime_ns();
    const GroundTruth& gt = sensors.truth().take(world, frame, slip_threshold_mm(cfg, phase));
    KeptTruth kt;
    kt.frame = frame;
    kt.t = world.time();
    kt.phase = phase;
    kt.truth = gt;
    kt.truth.twist_cycle = twist_cycle;
    for (auto& ft : kt.truth.fingertips)
      ft.camera_timestamp_ns = send_ns;
    for (std::size_t i = 0; i < kFingertips; ++i) {
      if (!cameras[i]->publish(sensors.render(i, gt.fingertips[i]).view(), frame, send_ns)) {
        util::log_warn("camera {}: a receiver set another format; frame not published", ids[i]);
      }
    }
    ++c.frames_rendered;
    if (const std::int64_t published_ns = util::realtime_ns(); published_ns > send_ns) {
      ++c.late_publishes;
      util::log_debug(
          "frame {} published {:.2f} ms after its send instant: started {:.2f} ms before it, "
          "world {:.2f} ms, images {:.2f} ms",
          frame, static_cast<double>(published_ns - send_ns) * 1e-6,
          static_cast<double>(send_ns - started_ns) * 1e-6,
          static_cast<double>(stepped_ns - started_ns) * 1e-6,
          static_cast<double>(published_ns - stepped_ns) * 1e-6);
    }
    scorer.add_truth(frame - first_frame, kt.t, kt.truth, {phase, twist_cycle},
                     frame_pose(world, transport));
    if (truth_pub) {
      fill_truth_message(kt.truth, util::realtime_ns(), *truth_env.mutable_ground_truth());
      wire::encode(truth_env, out);
      truth_pub->send(wire::kTruthTopic, wire::bytes_of(out));
    }
    kept.push_back(std::move(kt));
    while (kept.size() > 64)
      kept.pop_front();

    const std::int64_t after = util::realtime_ns();
    if (have_peer) {
      wire::fill_arm_state(arm_state_of(world, after, last_command), wire_ids,
                           *state_env.mutable_arm_state());
      if (deadman_tripped) state_env.mutable_arm_state()->add_faults(v1::ARM_FAULT_DEADMAN);
      wire::encode(state_env, out);
      arm.send(peer, wire::bytes_of(out));
      check_deadman(after);
    } else if (after - start_ns > static_cast<std::int64_t>(opt.wait_for_hand_s * 1e9)) {
      rep.end_reason = "no hand_node";
      break;
    }

    if (world.cap().dropped && dropped_at_ns < 0) dropped_at_ns = after;
    if (ended && after - ended_at_ns >= static_cast<std::int64_t>(sc.settle_after_done_s * 1e9))
      break;
    if (dropped_at_ns >= 0 && after - dropped_at_ns >= 500'000'000) {
      rep.end_reason = "dropped";
      break;
    }
    if (after - start_ns >= max_ns) break;
    if (!run.physics_finite) {
      rep.end_reason = "physics";
      break;
    }
    ++frame;
  }
  if (util::stop_requested() && !ended) rep.end_reason = "stopped";
  scorer.finish(world.cap().dropped, static_cast<double>(util::realtime_ns() - start_ns) * 1e-9,
                frame - first_frame);
  if (ended && rep.completed) rep.end_reason = "done";
  if (!latencies_ms.empty()) {
    result.latency_samples = latencies_ms.size();
    rep.latency_ms = Report::Latency{nearest_rank_percentile(latencies_ms, 0.50),
                                     nearest_rank_percentile(latencies_ms, 0.99),
                                     *std::max_element(latencies_ms.begin(), latencies_ms.end())};
  }
  util::log_info(
      "frames rendered {} (late {}, published late {}), scored {} (unmatched {}, incomplete {}), "
      "commands {} (refused {}), deadman trips {}, events {}",
      c.frames_rendered, c.late_renders, c.late_publishes, c.frames_scored, c.frames_unmatched,
      c.frames_incomplete, c.commands, c.invalid_commands, c.deadman_trips, c.events);
  return result;
}

std::string hand_controller_yaml(const Scenario& sc) {
  const control::Config cfg = scenario_controller_config(sc);
  std::string o = "controller:\n";
  const auto num = [&o](const char* key, double v) { o += fmt::format("  {}: {}\n", key, v); };
  num("cap_x_m", cfg.cap_x_m);
  num("cap_y_m", cfg.cap_y_m);
  num("bottle_x_m", cfg.bottle_x_m);
  num("bottle_y_m", cfg.bottle_y_m);
  o += fmt::format("  tighten_clockwise: {}\n", cfg.tighten_clockwise ? "true" : "false");
  bool stale_set = false;
  for (const auto& [key, v] : sc.controller) {
    num(key.c_str(), v);
    stale_set = stale_set || key == "stale_after_s";
  }
  // Stale after three frame periods without a whole frame: the hold comes within 3 periods.
  if (!stale_set) num("stale_after_s", 3.0 / sc.camera.fps);
  return o;
}

void write_node_configs(const Scenario& sc, const std::filesystem::path& dir,
                        const RealtimeOptions& opt) {
  World world(sc.world);
  const auto normals = world.element_normals();
  CameraParams cam = sc.camera;
  const auto& ids = kFingertipIds;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    config::save_calibration(dir / (std::string(ids[i]) + ".yaml"),
                             make_calibration(ids[i], cam, sc.optics, normals));
  }
  std::string sensor = fmt::format(
      "# sensor_node for the rig's scenario {} (written by rig --write-configs)\n"
      "format: tactile-sensor/1\n"
      "publish: tcp://*:5555\n"
      "measurement: {{reference_frames: {}}}\n"
      "cameras:\n",
      sc.source, sc.optics.reference_frames);
  for (std::size_t i = 0; i < kFingertips; ++i) {
    // The reference is saved on first capture and loaded on a restart: a sensor_node restarted
    // while the hand squeezes never takes a reference under load.
    sensor += fmt::format(
        "  - {{sensor_id: {}, camera: {}, calibration: {}.yaml, fps: {}, reference_cache: "
        "state/{}-reference.pgm}}\n",
        ids[i], opt.camera_addresses[i], ids[i], sc.camera.fps, ids[i]);
  }
  util::write_file_atomic(dir / "sensor_node.yaml", sensor);
  std::string hand = fmt::format(
      "# hand_node for the rig's scenario {} (written by rig --write-configs)\n"
      "format: tactile-hand/1\n"
      "fingertips:\n"
      "  - {{sensor_id: left, calibration: left.yaml}}\n"
      "  - {{sensor_id: right, calibration: right.yaml}}\n"
      "subscribe: [tcp://127.0.0.1:5555]\n"
      "arm: tcp://127.0.0.1:5556\n"
      "events: tcp://*:5558\n"
      "# The arm controller's deadman is {:.0f} ms: stay well inside it when idle.\n"
      "heartbeat_period_s: {}\n"
      "# The rig's two cameras expose together: run the controller on both frames of an\n"
      "# exposure at once, waiting at most 0.4 periods for the second.\n"
      "pair_window_s: {}\n"
      "# Between frames the controller runs only when a frame is half a period late: its timed\n"
      "# transitions run on frames and answer fresh ones.\n"
      "control_period_s: {}\n",
      sc.source, opt.deadman_s * 1e3, opt.deadman_s / 4, 0.4 / sc.camera.fps, 1.5 / sc.camera.fps);
  hand += hand_controller_yaml(sc);
  util::write_file_atomic(dir / "hand_node.yaml", hand);
}

}  // namespace tactile::rig
