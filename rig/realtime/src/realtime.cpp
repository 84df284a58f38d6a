#include "tactile/rig/realtime.hpp"

#include <fmt/format.h>
#include <sys/timerfd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include "tactile/arm/arm_server.hpp"
#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/camera/private_network.hpp"
#include "tactile/control/config.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/rig/arm_link.hpp"
#include "tactile/rig/control_link.hpp"
#include "tactile/rig/optics.hpp"
#include "tactile/rig/scenario_run.hpp"
#include "tactile/rig/scoring.hpp"
#include "tactile/rig/sensors.hpp"
#include "tactile/rig/truth.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/fd.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/host_load.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::rig {
namespace {

using std::chrono::milliseconds;

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

// Sends of one image a truth keeps the block ids of: a camera sends an image again only while
// the rig renders nothing newer (it runs late), rarely more than once or twice.
constexpr std::size_t kMaxSends = 8;
// A truth not yet published when both cameras have not sent anything newer this many periods
// after its send instant (no receiver streams, or the rig fell behind) is published with the
// block ids known by then.
constexpr std::int64_t kTruthWaitPeriods = 4;

// A truth kept until the measured frames of its instant arrive (a few frame periods), and
// published once the cameras have sent its images (their block ids known).
struct KeptTruth {
  std::uint64_t frame = 0;
  std::int64_t send_ns = 0;  // the instant the cameras send it: its camera timestamp
  double t = 0;
  control::Phase phase = control::Phase::kIdle;  // the controller's, when it was taken
  control::ArmMotion arm;  // the arm's motion from its reported poses, when it was taken
  GroundTruth truth;
  std::array<bool, kFingertips> scored{};
  // The block ids each fingertip's camera sent this image with, in order.
  std::array<std::array<std::uint64_t, kMaxSends>, kFingertips> block_ids{};
  std::array<std::size_t, kFingertips> sends{};
  bool published = false;
};

// The wire's GroundTruth of a kept truth: each fingertip with the block ids its camera sent the
// image with (docs/rig.md, "Joining truth and frames").
void fill_truth_message(const KeptTruth& kept, std::int64_t now_ns, v1::GroundTruth& out) {
  const GroundTruth& gt = kept.truth;
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
    const std::size_t sends = kept.sends[i];
    t.set_camera_frame_id(sends > 0 ? kept.block_ids[i][0] : 0);
    t.clear_resent_camera_frame_ids();
    for (std::size_t s = 1; s < sends; ++s)
      t.add_resent_camera_frame_ids(kept.block_ids[i][s]);
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

// What one camera sent, from its thread to the run's: per send the rendered frame and the
// GigE Vision block id. A fixed ring under a lock held for a copy; a full ring drops the send
// (counted: that frame then joins its truth by timestamp only).
class SentQueue {
 public:
  struct Sent {
    std::uint64_t frame = 0;
    std::uint64_t block_id = 0;
  };
  void push(Sent s) noexcept {
    const std::lock_guard lock(mutex_);
    if (size_ == ring_.size()) {
      ++dropped_;
      return;
    }
    ring_[(head_ + size_) % ring_.size()] = s;
    ++size_;
  }
  bool pop(Sent& s) noexcept {
    const std::lock_guard lock(mutex_);
    if (size_ == 0) return false;
    s = ring_[head_];
    head_ = (head_ + 1) % ring_.size();
    --size_;
    return true;
  }
  std::uint64_t dropped() const noexcept {
    const std::lock_guard lock(mutex_);
    return dropped_;
  }

 private:
  mutable std::mutex mutex_;
  std::array<Sent, 256> ring_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::uint64_t dropped_ = 0;
};

// A whole real-time run: the world stepped to the wall clock, the cameras fed, the arm link
// served, sensor_node's frames and hand_node's events scored. One object per run: its members
// are the run's state, its methods the loop's parts. The world's arm is the backend of the arm
// controller (arm::ArmServer): read, write and hold step the world to their instant first.
class RealtimeRun final : private arm::ArmBackend {
 public:
  RealtimeRun(const Scenario& sc, const RealtimeOptions& opt);
  RealtimeResult run();

 private:
  void advance_to(std::int64_t t_ns);
  // arm::ArmBackend.
  wire::ArmStateData read(std::int64_t now_ns) override;
  bool write(const wire::ReceivedCommand& command, std::int64_t now_ns) override;
  void hold(std::int64_t now_ns) override;
  void on_frame();
  void on_event();
  // Serves the sockets until `render_ns` (or a stop).
  void serve_until(std::int64_t render_ns);
  // Renders and publishes frame `frame_` for its send instant and keeps its truth.
  void render_frame(std::int64_t send_ns);
  // Notes the block ids the cameras sent kept truths with.
  void take_sent();
  // Publishes, in order, the kept truths whose images the cameras are done sending (both sent a
  // newer one, or kTruthWaitPeriods passed); with `all`, every kept truth not yet published.
  void publish_sent_truths(std::int64_t now_ns, bool all);
  void publish_truth(KeptTruth& kept);
  // Sends the peer the arm's state. False when the run ends: no hand_node came.
  bool answer_arm(std::int64_t now_ns);
  // True when the run ends after this frame.
  bool ended_after_frame(std::int64_t now_ns);
  void finish();
  // Records the machine's steal and load over the run and logs them beside the latency, with a
  // sentence when they explain it (run-system prints these lines).
  void log_latency_and_machine();

  const RealtimeOptions& opt_;
  RealtimeResult result_;
  RealtimeCounters& c_ = result_.counters;
  Report& rep_ = result_.run.report;
  const double dt_;
  const std::int64_t period_ns_;
  const std::int64_t lead_ns_;
  CameraParams cam_;
  // The world, sensors, truth, scorer and end rules, as the lockstep runner has them.
  ScenarioRun run_;
  // Before the cameras: their threads push into it until they are destroyed.
  std::array<SentQueue, kFingertips> sent_;
  std::array<std::uint64_t, kFingertips> newest_sent_{};  // the newest frame each camera sent
  std::vector<std::unique_ptr<camera::FakeGvCamera>> cameras_;

  zmq::context_t ctx_;
  arm::ArmServer arm_;
  std::optional<wire::Publisher> truth_pub_;
  wire::Subscriber frames_;
  std::optional<wire::Subscriber> events_;
  // Wakes the serving loop at the instant to render: ZeroMQ's poll counts whole milliseconds,
  // and a timeout rounded up started the frame up to a millisecond late (images then published
  // after their send instant), one rounded down would spin through the last millisecond.
  const WakeTimer render_timer_;

  // Reused buffers.
  wire::TopicMessage msg_;
  wire::EnvelopeDecoder decoder_;
  v1::Envelope truth_env_;
  std::string out_;
  std::array<wire::ReceivedFrame, kFingertips> measured_;
  std::deque<KeptTruth> kept_;
  std::vector<double> latencies_ms_;

  std::int64_t start_ns_ = 0;
  util::MachineLoadWindow machine_;  // the host's steal and load over the run
  control::Phase phase_ = control::Phase::kIdle;
  std::uint32_t twist_cycle_ = 0;
  std::uint64_t frame_ = 0;
  std::uint64_t first_frame_ = 0;
};

arm::ArmServerOptions arm_server_options(const RealtimeOptions& opt) {
  arm::ArmServerOptions o;
  o.endpoint = opt.arm_endpoint;
  o.security = opt.arm_security;
  o.deadman_s = opt.deadman_s;
  o.fingertip_ids = {kFingertipIds[0], kFingertipIds[1]};
  return o;
}

CameraParams realtime_camera(const Scenario& sc, const RealtimeOptions& opt) {
  CameraParams cam = sc.camera;
  cam.refresh_outside_disks = opt.full_noise;
  return cam;
}

RealtimeRun::RealtimeRun(const Scenario& sc, const RealtimeOptions& opt)
    : opt_(opt),
      dt_(sc.step_s()),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / sc.camera.fps))),
      lead_ns_(std::min(static_cast<std::int64_t>(opt.render_lead_s * 1e9), period_ns_ * 3 / 4)),
      cam_(realtime_camera(sc, opt)),
      run_(sc, cam_, result_.run, opt.record_series),
      arm_(ctx_, arm_server_options(opt), *this),
      frames_(ctx_, opt.observe_frames, {wire::kFrameTopicPrefix},
              opt.observe_security ? &*opt.observe_security : nullptr) {
  // Sensors: calibrations (written for sensor_node and hand_node) and cameras.
  const auto& ids = kFingertipIds;
  if (!opt.calibration_dir.empty())
    save_calibrations(opt.calibration_dir, result_.run.calibrations);
  const auto serve_cameras = [&] {
    for (std::size_t i = 0; i < kFingertips; ++i) {
      camera::FakeGvCameraOptions fo;
      fo.address = opt.camera_addresses[i];
      fo.serial = opt.camera_serials[i];
      fo.width = cam_.width;
      fo.height = cam_.height;
      fo.pixel_format = cam_.bit_depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
      fo.frame_rate_hz = cam_.fps;
      cameras_.push_back(std::make_unique<camera::FakeGvCamera>(fo));
      // An image the camera sent with its own block id: the id sensor_node publishes the frame
      // with. A frame before the first image or in another format carries no image of ours.
      cameras_.back()->set_sent_observer([queue = &sent_[i]](const camera::SentFrame& s) {
        if (s.format_matched && s.frame_id != 0) queue->push({s.frame_id, s.block_id});
      });
      util::log_info("camera {} ({}) serving on {}{}", ids[i], fo.serial, fo.address,
                     opt.camera_netns.empty() ? "" : " in network namespace " + opt.camera_netns);
    }
  };
  // The cameras' sockets (and the Aravis threads that serve them) are made where they are
  // created: in the camera namespace when one is named.
  if (opt.camera_netns.empty())
    serve_cameras();
  else
    camera::run_in_network_namespace(opt.camera_netns, serve_cameras);

  // Sockets.
  if (!opt.truth_endpoint.empty())
    truth_pub_.emplace(ctx_, opt.truth_endpoint,
                       opt.truth_security ? &*opt.truth_security : nullptr);
  if (!opt.observe_events.empty())
    events_.emplace(ctx_, std::vector<std::string>{opt.observe_events},
                    std::vector<std::string>{wire::kEventTopic},
                    opt.observe_events_security ? &*opt.observe_events_security : nullptr);
  util::log_info("arm controller on {}, ground truth on {}, deadman {:.0f} ms", arm_.endpoint(),
                 truth_pub_ ? truth_pub_->endpoint() : std::string("(none)"), opt.deadman_s * 1e3);
  if (opt.on_ready) opt.on_ready();

  for (std::size_t i = 0; i < kFingertips; ++i)
    measured_[i].elements.resize(kElementsPerFingertip);
  latencies_ms_.reserve(1 << 16);
}

// Steps the world until its clock reaches the wall-clock instant `t_ns`.
void RealtimeRun::advance_to(std::int64_t t_ns) {
  run_.advance_to(static_cast<double>(t_ns - start_ns_) * 1e-9, dt_);
}

wire::ArmStateData RealtimeRun::read(std::int64_t now_ns) {
  return arm_state_of(run_.world(), now_ns, 0);  // the server fills in the last command's sequence
}

bool RealtimeRun::write(const wire::ReceivedCommand& cmd, std::int64_t now_ns) {
  for (std::size_t i = 0; i < cmd.answers.count; ++i) {
    const std::int64_t cam_ts = cmd.answers.refs[i].camera_timestamp_ns;
    if (cam_ts <= 0) continue;
    const double ms = static_cast<double>(now_ns - cam_ts) * 1e-6;
    latencies_ms_.push_back(ms);
    // Answers older than a period are the tail of latency_ms: say which they were.
    if (now_ns - cam_ts > period_ns_) {
      util::log_debug("command {} answered frame {} of fingertip {} {:.2f} ms after its exposure",
                      cmd.sequence, cmd.answers.refs[i].sequence, cmd.answers.refs[i].fingertip,
                      ms);
    }
  }
  advance_to(now_ns);  // the command acts from the moment it arrived
  return run_.apply(cmd.command);
}

void RealtimeRun::hold(std::int64_t now_ns) {
  advance_to(now_ns);  // the hold acts from the moment it was decided
  run_.apply(control::Command::hold());
}

void RealtimeRun::on_frame() {
  if (decoder_.decode(msg_.payload) != wire::DecodeStatus::kOk) return;
  const v1::Envelope& env = decoder_.envelope();
  if (!env.has_tactile_frame()) return;
  const v1::TactileFrame& f = env.tactile_frame();
  const std::size_t tip = f.sensor_id() == kFingertipIds[0]   ? 0
                          : f.sensor_id() == kFingertipIds[1] ? 1
                                                              : kFingertips;
  if (tip == kFingertips) return;
  if (f.status() != v1::FRAME_STATUS_COMPLETE) {
    if (f.status() != v1::FRAME_STATUS_NO_REFERENCE) ++c_.frames_incomplete;
    return;
  }
  if (wire::read_tactile_frame(f, result_.run.calibrations[tip], measured_[tip]) !=
      wire::DecodeStatus::kOk)
    return;
  const auto it = std::find_if(kept_.begin(), kept_.end(), [&](const KeptTruth& k) {
    return k.truth.fingertips[tip].camera_timestamp_ns == f.camera_timestamp_ns();
  });
  if (it == kept_.end() || it->scored[tip]) {
    ++c_.frames_unmatched;  // an image the camera sent again, or one older than the window
    return;
  }
  it->scored[tip] = true;
  ++c_.frames_scored;
  run_.scorer().add_measurement(tip, it->frame - first_frame_, measured_[tip].elements,
                                it->truth.fingertips[tip], it->phase, it->arm);
}

void RealtimeRun::on_event() {
  if (decoder_.decode(msg_.payload) != wire::DecodeStatus::kOk) return;
  const v1::Envelope& env = decoder_.envelope();
  if (!env.has_event()) return;
  const v1::Event& e = env.event();
  ++c_.events;
  const auto p = wire::phase_from_string(e.phase());
  if (p) phase_ = *p;
  twist_cycle_ = std::max(twist_cycle_, e.cycle());
  const double t = static_cast<double>(util::realtime_ns() - start_ns_) * 1e-9;
  control::Event ce;
  ce.kind = static_cast<control::EventKind>(e.kind());
  ce.phase = p.value_or(phase_);
  ce.cycle = e.cycle();
  for (std::size_t i = 0; i < kFingertips; ++i) {
    if (e.sensor_id() == kFingertipIds[i]) ce.fingertip = static_cast<std::int8_t>(i);
  }
  ce.value = e.value();
  ce.text = e.text().c_str();  // copied by the scorer
  run_.scorer().add_event(ce, t);
  if (e.kind() == v1::EVENT_KIND_DONE || e.kind() == v1::EVENT_KIND_ABORTED) run_.task_ended(t);
}

void RealtimeRun::serve_until(std::int64_t render_ns) {
  std::array<zmq::socket_ref, 3> sockets{arm_.socket(), frames_.socket(),
                                         events_ ? events_->socket() : frames_.socket()};
  for (;;) {
    std::int64_t now = util::realtime_ns();
    const std::int64_t wait_ns = render_ns - now;
    if (wait_ns > 0) {
      render_timer_.arm_at(render_ns);
      wire::poll_readable(sockets, milliseconds(std::min<std::int64_t>(wait_ns / 1000000 + 1, 5)),
                          render_timer_.fd());
    }
    now = util::realtime_ns();
    while (arm_.serve_one(util::realtime_ns())) {
    }
    while (frames_.receive(msg_, milliseconds(0)))
      on_frame();
    while (events_ && events_->receive(msg_, milliseconds(0)))
      on_event();
    arm_.check_deadman(util::realtime_ns());
    take_sent();
    publish_sent_truths(util::realtime_ns(), false);
    if (now >= render_ns || util::stop_requested()) break;
  }
}

void RealtimeRun::render_frame(std::int64_t send_ns) {
  const std::int64_t started_ns = util::realtime_ns();
  advance_to(send_ns);
  const std::int64_t stepped_ns = util::realtime_ns();
  const GroundTruth& gt = run_.take_truth(frame_, phase_);
  KeptTruth kt;
  kt.frame = frame_;
  kt.send_ns = send_ns;
  kt.t = run_.world().time();
  kt.phase = phase_;
  kt.arm = run_.arm_motion(kt.t);
  kt.truth = gt;
  kt.truth.twist_cycle = twist_cycle_;
  for (auto& ft : kt.truth.fingertips)
    ft.camera_timestamp_ns = send_ns;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    if (!cameras_[i]->publish(run_.sensors().render(i, gt.fingertips[i]).view(), frame_, send_ns)) {
      util::log_warn("camera {}: a receiver set another format; frame not published",
                     kFingertipIds[i]);
    }
  }
  ++c_.frames_rendered;
  if (const std::int64_t published_ns = util::realtime_ns(); published_ns > send_ns) {
    ++c_.late_publishes;
    util::log_debug(
        "frame {} published {:.2f} ms after its send instant: started {:.2f} ms before it, "
        "world {:.2f} ms, images {:.2f} ms",
        frame_, static_cast<double>(published_ns - send_ns) * 1e-6,
        static_cast<double>(send_ns - started_ns) * 1e-6,
        static_cast<double>(stepped_ns - started_ns) * 1e-6,
        static_cast<double>(published_ns - stepped_ns) * 1e-6);
  }
  run_.score_truth(frame_ - first_frame_, kt.t, kt.truth, {phase_, twist_cycle_});
  kept_.push_back(std::move(kt));
  while (kept_.size() > 64) {
    if (!kept_.front().published) publish_truth(kept_.front());
    kept_.pop_front();
  }
}

void RealtimeRun::take_sent() {
  SentQueue::Sent s;
  for (std::size_t i = 0; i < kFingertips; ++i) {
    while (sent_[i].pop(s)) {
      newest_sent_[i] = std::max(newest_sent_[i], s.frame);
      const auto it = std::find_if(kept_.rbegin(), kept_.rend(),
                                   [&](const KeptTruth& k) { return k.frame == s.frame; });
      if (it == kept_.rend() || it->published || it->sends[i] == kMaxSends) {
        ++c_.sends_after_truth;
        continue;
      }
      it->block_ids[i][it->sends[i]++] = s.block_id;
    }
  }
}

void RealtimeRun::publish_sent_truths(std::int64_t now_ns, bool all) {
  for (KeptTruth& k : kept_) {
    if (k.published) continue;
    bool done = all || now_ns >= k.send_ns + kTruthWaitPeriods * period_ns_;
    if (!done) {
      done = true;
      for (std::size_t i = 0; i < kFingertips; ++i)
        done = done && newest_sent_[i] > k.frame;
    }
    if (!done) return;  // the later ones wait too: truth is published in frame order
    publish_truth(k);
  }
}

void RealtimeRun::publish_truth(KeptTruth& kept) {
  kept.published = true;
  if (!truth_pub_) return;
  fill_truth_message(kept, util::realtime_ns(), *truth_env_.mutable_ground_truth());
  wire::encode(truth_env_, out_);
  truth_pub_->send(wire::kTruthTopic, wire::bytes_of(out_));
}

bool RealtimeRun::answer_arm(std::int64_t now_ns) {
  if (arm_.send_state(now_ns)) return true;
  if (now_ns - start_ns_ > static_cast<std::int64_t>(opt_.wait_for_hand_s * 1e9)) {
    rep_.end_reason = "no hand_node";
    return false;
  }
  return true;
}

bool RealtimeRun::ended_after_frame(std::int64_t now_ns) {
  // Frames are counted in periods of the wall clock since the start, rendered or skipped.
  return run_.ended_after_frame(frame_ - first_frame_ + 1,
                                static_cast<double>(now_ns - start_ns_) * 1e-9);
}

void RealtimeRun::finish() {
  // The cameras stop sending before the last truths go out, so every frame sent has its block
  // id in the truth published.
  cameras_.clear();
  take_sent();
  publish_sent_truths(0, true);
  for (const SentQueue& q : sent_)
    c_.sends_after_truth += q.dropped();
  const arm::ArmServerCounters arm = arm_.counters();
  c_.commands = arm.commands;
  c_.invalid_commands = arm.refused();
  c_.deadman_trips = arm.deadman_trips;
  if (util::stop_requested() && !run_.task_has_ended()) rep_.end_reason = "stopped";
  run_.finish(static_cast<double>(util::realtime_ns() - start_ns_) * 1e-9, frame_ - first_frame_);
  if (!latencies_ms_.empty()) {
    result_.latency_samples = latencies_ms_.size();
    result_.latency_ms = latencies_ms_;
    rep_.latency_ms = Report::Latency{
        nearest_rank_percentile(latencies_ms_, 0.50), nearest_rank_percentile(latencies_ms_, 0.99),
        *std::max_element(latencies_ms_.begin(), latencies_ms_.end())};
  }
  log_latency_and_machine();
  util::log_info(
      "frames rendered {} (late {}, published late {}), scored {} (unmatched {}, incomplete {}), "
      "commands {} (refused {}), deadman trips {}, events {}, sends after their truth {}",
      c_.frames_rendered, c_.late_renders, c_.late_publishes, c_.frames_scored, c_.frames_unmatched,
      c_.frames_incomplete, c_.commands, c_.invalid_commands, c_.deadman_trips, c_.events,
      c_.sends_after_truth);
}

void RealtimeRun::log_latency_and_machine() {
  rep_.machine = machine_.end();
  const std::string machine = util::describe(*rep_.machine);
  if (rep_.latency_ms) {
    const Report::Latency& l = *rep_.latency_ms;
    util::log_info("latency p50 {:.1f} ms, p99 {:.1f} ms, max {:.1f} ms; machine: {}", l.p50, l.p99,
                   l.max, machine);
  } else {
    util::log_info("latency not measured; machine: {}", machine);
  }
  const std::string why = util::latency_explanation(*rep_.machine);
  if (!why.empty()) util::log_warn("{}", why);
}

RealtimeResult RealtimeRun::run() {
  machine_.begin();
  start_ns_ = util::realtime_ns();
  frame_ = static_cast<std::uint64_t>((start_ns_ + lead_ns_) / period_ns_) + 1;
  first_frame_ = frame_;
  while (!util::stop_requested()) {
    const std::int64_t send_ns = static_cast<std::int64_t>(frame_) * period_ns_;
    serve_until(send_ns - lead_ns_);
    const std::int64_t now = util::realtime_ns();
    if (now > send_ns) {
      // Too late for this frame: the camera sends the previous image again. Skip to the next.
      ++c_.late_renders;
      frame_ = static_cast<std::uint64_t>((now + lead_ns_) / period_ns_) + 1;
      continue;
    }
    if (opt_.late_every > 0 && frame_ % opt_.late_every == 0) {
      // Late on purpose (--late-every): the same resend as above, on every run.
      ++c_.late_renders;
      ++frame_;
      continue;
    }
    render_frame(send_ns);  // the world at the instant the camera sends the frame
    const std::int64_t after = util::realtime_ns();
    if (!answer_arm(after) || ended_after_frame(after)) break;
    ++frame_;
  }
  finish();
  return std::move(result_);
}

}  // namespace

RealtimeResult run_realtime(const Scenario& sc, const RealtimeOptions& opt) {
  return RealtimeRun(sc, opt).run();
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
  o += fmt::format("  slip_detector: {}\n", control::to_string(cfg.slip_detector));
  o += fmt::format("  grip: {}\n", control::to_string(cfg.grip));
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
  const World world(sc.world);
  save_calibrations(dir, simulated_calibrations(sc, sc.camera, world.element_normals()));
  const auto& ids = kFingertipIds;
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
        "  - {{sensor_id: {}, camera: {}, calibration: {}.yaml, fps: {}, {}reference_cache: "
        "state/{}-reference.pgm}}\n",
        ids[i], opt.camera_addresses[i], ids[i], sc.camera.fps,
        opt.camera_packet_size > 0 ? fmt::format("packet_size: {}, ", opt.camera_packet_size)
                                   : std::string(),
        ids[i]);
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
