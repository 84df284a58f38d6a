#include "hand_node.hpp"

#include <algorithm>
#include <chrono>

#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile::hand {
namespace {

std::int64_t seconds_to_ns(double s) {
  return static_cast<std::int64_t>(s * 1e9);
}

// While the task waits to start, what it waits for is said again this often (a hand_node left
// without an arm controller or a camera would otherwise fall silent after one line).
constexpr std::int64_t kWaitingReportNs = 5'000'000'000;

}  // namespace

HandNode::HandNode(HandConfig cfg, zmq::context_t& ctx)
    : cfg_(std::move(cfg)),
      ids_{cfg_.fingertips[0].sensor_id, cfg_.fingertips[1].sensor_id},
      sub_(ctx, cfg_.subscribe, {wire::frame_topic(ids_[0]), wire::frame_topic(ids_[1])},
           cfg_.sensor_security ? &*cfg_.sensor_security : nullptr),
      arm_(ctx, cfg_.arm, cfg_.arm_security ? &*cfg_.arm_security : nullptr),
      controller_(cfg_.controller),
      pairing_(seconds_to_ns(cfg_.pair_window_s)),
      // A heartbeat that could not go out is tried again a tenth of a period later.
      link_({seconds_to_ns(cfg_.heartbeat_period_s), seconds_to_ns(cfg_.arm_timeout_s),
             seconds_to_ns(cfg_.arm_lost_s), seconds_to_ns(cfg_.heartbeat_period_s) / 10}),
      start_(static_cast<std::uint64_t>(cfg_.start_after_frames), kWaitingReportNs),
      freshness_(seconds_to_ns(cfg_.controller.stale_after_s)),
      period_ns_(seconds_to_ns(cfg_.control_period_s)) {
  if (!cfg_.events.empty())
    events_.emplace(ctx, cfg_.events, cfg_.events_security ? &*cfg_.events_security : nullptr);
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    frames_[i].elements.resize(cfg_.fingertips[i].calibration.elements.size());
  }
}

wire::Answers HandNode::answers() const {
  wire::Answers a;
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    if (!freshness_.has_frame(i)) continue;
    a.add({static_cast<std::int8_t>(i), frames_[i].header.sequence,
           frames_[i].header.camera_timestamp_ns});
  }
  return a;
}

bool HandNode::send_envelope() {
  wire::encode(out_, out_bytes_);
  if (arm_.send(wire::bytes_of(out_bytes_))) return true;
  ++counters_.commands_blocked;
  return false;
}

// The wire's timestamps (the command's, the heartbeat's, the Decision's, a frame's receipt) are
// CLOCK_REALTIME read when the message is made or received: they measure latency, they decide
// nothing. Every decision takes the loop's monotonic now_ns.
void HandNode::send_command(const control::Command& c, std::int64_t now_ns, bool names_frames) {
  v1::ArmCommand& cmd = *out_.mutable_arm_command();
  wire::fill_arm_command(c, ++command_sequence_, util::realtime_ns(),
                         names_frames ? answers() : wire::Answers{}, ids_, cmd);
  // When each answered frame arrived here: splits latency into transport and control.
  for (v1::FrameRef& r : *cmd.mutable_answers())
    r.set_receive_timestamp_ns(r.sensor_id() == ids_[0] ? received_ns_[0] : received_ns_[1]);
  link_.command_sent(c, now_ns, send_envelope());
  // A copy beside the events, as for ArmStates (the arm link itself is point to point).
  if (events_) events_->send(wire::kCommandTopic, wire::bytes_of(out_bytes_));
  ++counters_.commands;
}

void HandNode::send_heartbeat(std::int64_t now_ns) {
  auto* hb = out_.mutable_heartbeat();
  hb->set_time_ns(util::realtime_ns());
  hb->set_sender("hand_node");
  link_.heartbeat_sent(now_ns, send_envelope());
}

void HandNode::on_topic_message(std::int64_t now_ns) {
  const std::int64_t received_ns = util::realtime_ns();
  const auto status = decoder_.decode(msg_.payload);
  const v1::Envelope& in = decoder_.envelope();
  if (status != wire::DecodeStatus::kOk || !in.has_tactile_frame()) {
    ++counters_.undecodable;
    return;
  }
  const v1::TactileFrame& f = in.tactile_frame();
  int k = -1;
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    if (f.sensor_id() == ids_[i]) k = static_cast<int>(i);
  }
  if (k < 0) {
    ++counters_.undecodable;
    return;
  }
  const auto ki = static_cast<std::size_t>(k);
  wire::ReceivedFrame& frame = frames_[ki];
  // Decode into a scratch copy of the header first: an invalid or incomplete frame must not
  // replace the last whole one the controller holds.
  const wire::FrameHeader previous = frame.header;
  if (f.status() != v1::FRAME_STATUS_COMPLETE) {
    ++counters_.incomplete[ki];
    return;
  }
  // A frame of this fingertip still waits for its pair: the controller runs on it before this
  // one replaces it (no frame's displacement is skipped).
  if (pairing_.waiting(k)) {
    ++counters_.unpaired;
    step(now_ns, pairing_.take());
  }
  if (wire::read_tactile_frame(f, cfg_.fingertips[ki].calibration, frame) !=
      wire::DecodeStatus::kOk) {
    frame.header = previous;
    ++counters_.undecodable;
    return;
  }
  ++counters_.frames[ki];
  received_ns_[ki] = received_ns;
  const std::int64_t sent_ns = frame.header.receive_timestamp_ns;  // by sensor_node
  freshness_.arrived(ki, now_ns, sent_ns);
  const bool other_live = freshness_.live(1 - ki, now_ns, sent_ns);
  if (pairing_.arrived(k, sent_ns, now_ns, other_live)) step(now_ns, pairing_.take());
}

void HandNode::on_arm_message(std::int64_t now_ns) {
  if (decoder_.decode(arm_buf_) != wire::DecodeStatus::kOk) {
    ++counters_.undecodable;
    return;
  }
  const v1::Envelope& in = decoder_.envelope();
  if (in.has_arm_state()) {
    if (wire::read_arm_state(in.arm_state(), ids_, arm_state_) != wire::DecodeStatus::kOk) {
      ++counters_.undecodable;
      return;
    }
    ++counters_.arm_states;
    // Beside the events, for recordings and plots (the arm link itself is point to point).
    if (events_) events_->send(wire::kArmTopic, arm_buf_);
    const ArmLink::StateHeard h = link_.arm_state(arm_state_.deadman, now_ns);
    if (h.hold_began)
      util::log_warn("the arm controller's deadman held the arm: resuming the current motion");
    if (h.motion) send_command(*h.motion, now_ns);
    if (h.velocities) send_command(*h.velocities, now_ns);
    if (h.heard_again) util::log_info("arm controller heard again");
  } else if (in.has_heartbeat()) {
    if (link_.heartbeat_heard(now_ns)) util::log_info("arm controller heard again");
  } else {
    ++counters_.undecodable;
  }
}

bool HandNode::ready(std::int64_t now_ns) {
  if (start_.started()) return true;
  const TaskStart::Check c = start_.check(now_ns, link_.arm_heard(), counters_.frames);
  if (c.start) {
    util::log_info(
        "arm controller and both fingertips ({}, {}) are live ({} whole frames each): starting "
        "the task ({})",
        ids_[0], ids_[1], cfg_.start_after_frames, control::to_string(cfg_.controller.task));
    return true;
  }
  if (c.report_waiting) {
    util::log_info(
        "waiting for the arm controller at {} ({}) and {} whole tactile frames each of {} ({} so "
        "far, {} incomplete) and {} ({} so far, {} incomplete)",
        cfg_.arm, link_.arm_heard() ? "answering" : "not heard yet", cfg_.start_after_frames,
        ids_[0], counters_.frames[0], counters_.incomplete[0], ids_[1], counters_.frames[1],
        counters_.incomplete[1]);
  }
  return false;
}

void HandNode::step(std::int64_t now_ns, FramePairing::Fresh fresh) {
  if (!ready(now_ns)) return;
  last_update_ns_ = now_ns;
  control::ControllerInput in;
  bool any_stale = false;
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    control::FingertipInput& t = in.fingertips[i];
    t.elements = frames_[i].elements;
    t.normals = cfg_.fingertips[i].normals;
    t.sequence = frames_[i].header.sequence;
    t.camera_timestamp_ns = frames_[i].header.camera_timestamp_ns;
    t.fresh = fresh[i];
    t.stale = freshness_.stale(i, now_ns);
    any_stale = any_stale || t.stale;
  }
  if (any_stale && !stale_) ++counters_.stale_holds;
  stale_ = any_stale;
  in.arm = wire::to_feedback(arm_state_);
  in.now_s = static_cast<double>(now_ns - start_.start_ns()) * 1e-9;

  const control::ControllerOutput out = controller_.update(in);
  const std::int64_t decided_ns = util::realtime_ns();
  const bool sent = out.command.kind != control::CommandKind::kNone;
  if (sent) send_command(out.command, now_ns);
  if (events_ && (fresh[0] || fresh[1])) {
    // What this step decided on each fresh frame and when: every frame's decision is timed, not
    // only those a command answers.
    wire::Answers on;
    for (std::size_t i = 0; i < control::kFingertips; ++i) {
      if (fresh[i])
        on.add({static_cast<std::int8_t>(i), frames_[i].header.sequence,
                frames_[i].header.camera_timestamp_ns});
    }
    wire::fill_decision(out, decided_ns, on, received_ns_, sent ? command_sequence_ : 0, ids_,
                        *decision_env_.mutable_decision());
    wire::encode(decision_env_, out_bytes_);
    events_->send(wire::kDecisionTopic, wire::bytes_of(out_bytes_));
  }
  for (const control::Event& e : out.events) {
    ++counters_.events;
    const std::string where =
        e.fingertip >= 0 ? " " + ids_[static_cast<std::size_t>(e.fingertip)] : "";
    util::log_info("event {} [{}{}{}]{}{}", control::to_string(e.kind), control::to_string(e.phase),
                   e.cycle > 0 ? " cycle " + std::to_string(e.cycle) : "", where,
                   e.has_element ? " element " + std::to_string(e.element_id) : "",
                   e.text[0] != '\0' ? std::string(": ") + e.text : "");
    if (events_) {
      wire::fill_event(e, util::realtime_ns(), answers(), ids_, *event_env_.mutable_event());
      wire::encode(event_env_, out_bytes_);
      events_->send(wire::kEventTopic, wire::bytes_of(out_bytes_));
    }
  }
}

std::chrono::milliseconds HandNode::poll_wait(std::int64_t now_ns) const {
  std::int64_t until_tick = std::max<std::int64_t>(0, last_update_ns_ + period_ns_ - now_ns);
  if (pairing_.any_waiting())
    until_tick = std::max<std::int64_t>(0, pairing_.deadline_ns() - now_ns);
  // Heartbeats are due on time whatever the control period: the arm controller's deadman counts
  // on them (with control_period_s above the frame period, frames alone would wake this loop
  // only once a period).
  const std::int64_t until_heartbeat =
      std::max<std::int64_t>(0, link_.heartbeat_due_ns(now_ns) - now_ns);
  return std::chrono::milliseconds(
      std::min<std::int64_t>(std::min(until_tick, until_heartbeat) / 1000000 + 1, 50));
}

bool HandNode::tend_arm_link(std::int64_t now_ns) {
  const ArmLink::Due due = link_.due(now_ns);
  if (due.heartbeat) send_heartbeat(now_ns);
  if (due.arm_silent) {
    util::log_warn("no word from the arm controller for {:.1f} s",
                   static_cast<double>(due.silent_ns) * 1e-9);
  }
  if (!due.arm_lost) return true;
  // Gone, not slow: hold (should it come back, the arm stays where it is) and give up.
  send_command(control::Command::hold(), now_ns, false);
  util::log_error(
      "the arm controller at {} has been silent for {:.1f} s (arm_lost_s {}): holding and "
      "exiting",
      cfg_.arm, static_cast<double>(due.silent_ns) * 1e-9, cfg_.arm_lost_s);
  return false;
}

Outcome HandNode::run() {
  util::log_info("subscribing to {} sensor endpoint(s), arm controller at {}",
                 cfg_.subscribe.size(), cfg_.arm);
  if (events_) {
    util::log_info("events on {}{}", events_->endpoint(), cfg_.events_security ? " (CURVE)" : "");
  }
  std::array<zmq::socket_ref, 2> sockets{sub_.socket(), arm_.socket()};
  Outcome outcome = Outcome::kStopped;
  std::int64_t now = util::monotonic_ns();
  while (!util::stop_requested()) {
    const std::chrono::milliseconds wait = poll_wait(now);
    wire::poll_readable(sockets, wait);
    // The loop's one reading of the clock this turn: everything below decides on it.
    const std::int64_t woke = util::monotonic_ns();
    // Back more than a control period later than asked since the last turn began: this process
    // did not run (not scheduled, stopped). Frames sent meanwhile wait in its socket or are still
    // on their way through ZeroMQ's I/O thread: staleness does not count the time away, and the
    // time-driven step (which judges it) waits for one more short poll.
    const std::int64_t away_ns =
        woke - now - std::chrono::duration_cast<std::chrono::nanoseconds>(wait).count();
    const bool overslept = away_ns > period_ns_;
    if (overslept) freshness_.not_running(away_ns);
    now = woke;
    while (sub_.receive(msg_, std::chrono::milliseconds(0)))
      on_topic_message(now);
    while (arm_.receive(arm_buf_, std::chrono::milliseconds(0)))
      on_arm_message(now);
    // A frame waited its whole window without its pair: the controller runs on it alone.
    if (pairing_.due(now)) {
      ++counters_.unpaired;
      step(now, pairing_.take());
    }
    // Time-driven steps (timeouts, settling, staleness) run even when no frame arrives.
    if (!overslept && !pairing_.any_waiting() && now - last_update_ns_ >= period_ns_) step(now, {});
    if (!tend_arm_link(now)) {
      outcome = Outcome::kArmLost;
      break;
    }
    if (controller_.done()) {
      outcome = controller_.phase() == control::Phase::kDone ? Outcome::kDone : Outcome::kAborted;
      break;
    }
  }
  if (outcome == Outcome::kStopped) {
    util::log_info("stop requested: sending Stop to the arm");
    // Not computed from any frame: it names none (the arm controller counts the latency of
    // commands from the frames they name).
    send_command(control::Command::stop(), now, false);
  }
  util::log_info(
      "frames used {}/{}, skipped incomplete {}/{}, undecodable {}, commands {} (blocked {}), "
      "events {}, stale holds {}, frames run without their pair {}",
      counters_.frames[0], counters_.frames[1], counters_.incomplete[0], counters_.incomplete[1],
      counters_.undecodable, counters_.commands, counters_.commands_blocked, counters_.events,
      counters_.stale_holds, counters_.unpaired);
  return outcome;
}

}  // namespace tactile::hand
