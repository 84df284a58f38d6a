#include "latency_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <string_view>

#include "tactile/recording/log_reader.hpp"
#include "tactile/recording/log_writer.hpp"
#include "tactile/util/percentile.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile::bench {
namespace {

using FrameKey = std::pair<std::string, std::uint64_t>;  // sensor, sequence
// Per fingertip: (camera timestamp, any element truly sliding), in frame order.
using SlipTruth = std::map<std::string, std::vector<std::pair<std::int64_t, bool>>>;

// The captured messages, decoded after the run.
struct Decoded {
  std::map<FrameKey, FrameInfo> frames;
  std::vector<CommandInfo> commands;
  std::vector<DecisionInfo> decisions;
  std::vector<v1::Event> recompress;
  SlipTruth truth;
};

FrameInfo frame_info(const v1::TactileFrame& f) {
  return {f.sensor_id(),
          f.sequence(),
          f.status(),
          f.camera_timestamp_ns(),
          f.receive_timestamp_ns(),
          f.publish_timestamp_ns(),
          f.measure_time_us(),
          f.frames_skipped()};
}

CommandInfo command_info(const v1::ArmCommand& a) {
  const auto* oneof = a.GetDescriptor()->FindOneofByName("command");
  const auto* field = a.GetReflection()->GetOneofFieldDescriptor(a, oneof);
  CommandInfo ci{a.sequence(), a.send_timestamp_ns(), field ? field->name() : "none", {}};
  for (const v1::FrameRef& ref : a.answers())
    ci.answers.push_back(
        {ref.sensor_id(), ref.sequence(), ref.camera_timestamp_ns(), ref.receive_timestamp_ns()});
  return ci;
}

void add_truth(const v1::GroundTruth& gt, SlipTruth& truth) {
  for (const v1::FingertipTruth& ft : gt.fingertips()) {
    bool sliding = false;
    for (const v1::ElementTruth& e : ft.elements())
      sliding = sliding || e.sliding();
    truth[ft.sensor_id()].emplace_back(ft.camera_timestamp_ns(), sliding);
  }
}

// Counts one received TactileFrame: incomplete ones over the run, sequence gaps, statuses and
// sizes in the window.
class FrameTally {
 public:
  explicit FrameTally(PipelineResult& r) : r_(r) {}
  void add(const FrameInfo& fi, bool in_window, std::size_t bytes) {
    if (fi.status != v1::FRAME_STATUS_COMPLETE && fi.status != v1::FRAME_STATUS_NO_REFERENCE)
      r_.incomplete_run.push_back({{"sensor_id", fi.sensor},
                                   {"sequence", fi.sequence},
                                   {"status", v1::FrameStatus_Name(fi.status)},
                                   {"in_window", in_window}});
    auto [it, fresh] = last_seq_.try_emplace(fi.sensor, fi.sequence);
    if (!fresh) {
      if (in_window && fi.sequence > it->second + 1)
        r_.sequence_gaps += fi.sequence - it->second - 1;
      it->second = fi.sequence;
    }
    if (!in_window) return;
    ++r_.frames;
    r_.frames_skipped += fi.frames_skipped;
    if (fi.status == v1::FRAME_STATUS_COMPLETE) {
      ++r_.frames_complete;
      bytes_.push_back(static_cast<double>(bytes));
    } else if (fi.status != v1::FRAME_STATUS_NO_REFERENCE) {
      ++r_.frames_incomplete;
    }
  }
  const std::vector<double>& complete_bytes() const { return bytes_; }

 private:
  PipelineResult& r_;
  std::map<std::string, std::uint64_t> last_seq_;
  std::vector<double> bytes_;
};

Decoded decode_captured(const std::vector<Captured>& cap, const Window& w, PipelineResult& r) {
  wire::EnvelopeDecoder dec;
  Decoded d;
  FrameTally tally(r);
  std::vector<double> command_bytes;
  for (const Captured& c : cap) {
    if (dec.decode(c.payload) != wire::DecodeStatus::kOk) continue;
    const v1::Envelope& env = dec.envelope();
    const bool in_window = w.contains(c.receive_ns);
    if (env.has_tactile_frame()) {
      const FrameInfo fi = frame_info(env.tactile_frame());
      d.frames[{fi.sensor, fi.sequence}] = fi;
      tally.add(fi, in_window, c.payload.size());
    } else if (env.has_arm_command()) {
      d.commands.push_back(command_info(env.arm_command()));
      if (in_window) command_bytes.push_back(static_cast<double>(c.payload.size()));
    } else if (env.has_decision()) {
      DecisionInfo di{env.decision().time_ns(), {}};
      for (const v1::FrameRef& ref : env.decision().answers())
        di.answers.push_back({ref.sensor_id(), ref.sequence(), ref.camera_timestamp_ns(),
                              ref.receive_timestamp_ns()});
      d.decisions.push_back(std::move(di));
    } else if (env.has_event()) {
      ++r.events[v1::EventKind_Name(env.event().kind())];
      if (env.event().kind() == v1::EVENT_KIND_RECOMPRESS) d.recompress.push_back(env.event());
    } else if (env.has_ground_truth()) {
      add_truth(env.ground_truth(), d.truth);
    }
  }
  r.frame_bytes_p50 = static_cast<std::size_t>(percentile(tally.complete_bytes(), 0.5));
  r.command_bytes_p50 = static_cast<std::size_t>(percentile(command_bytes, 0.5));
  return d;
}

bool whole_in_window(const FrameInfo& f, const Window& w) {
  return f.status == v1::FRAME_STATUS_COMPLETE && w.contains(f.camera_ns);
}

// Camera -> sensor_node received, and received -> published, of the whole frames in the window.
void frame_stages(const std::map<FrameKey, FrameInfo>& frames, const Window& w, PipelineResult& r) {
  std::vector<double> gige;
  std::vector<std::pair<std::int64_t, std::int64_t>> gige_ns;
  std::vector<double> measure;
  std::vector<double> core;
  for (const auto& [key, f] : frames) {
    if (!whole_in_window(f, w)) continue;
    gige.push_back(static_cast<double>(f.receive_ns - f.camera_ns) * 1e-6);
    gige_ns.emplace_back(f.camera_ns, f.receive_ns);
    measure.push_back(static_cast<double>(f.publish_ns - f.receive_ns) * 1e-6);
    core.push_back(f.measure_us * 1e-3);
  }
  r.gige = dist(gige);
  r.gige_pair = later_of_pair(gige_ns);
  r.gige_negative = static_cast<std::uint64_t>(
      std::count_if(gige.begin(), gige.end(), [](double x) { return x < 0; }));
  r.measure = dist(measure);
  r.measure_core = dist(core);
}

// Gaps between consecutive published frames of a sensor, against hand_node's staleness limit
// (three frame periods, as rig --write-configs sets it): in camera time and in publish time.
void frame_gaps(const std::map<FrameKey, FrameInfo>& frames, const Window& w, double fps,
                PipelineResult& r) {
  const auto stale_ns = static_cast<std::int64_t>(3e9 / fps);
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> prev;  // camera, publish
  for (const auto& [key, f] : frames) {
    if (!whole_in_window(f, w)) continue;
    auto [it, first] = prev.try_emplace(f.sensor, f.camera_ns, f.publish_ns);
    if (first) continue;
    const std::int64_t cam_gap = f.camera_ns - it->second.first;
    const std::int64_t pub_gap = f.publish_ns - it->second.second;
    r.max_camera_gap_ms = std::max(r.max_camera_gap_ms, static_cast<double>(cam_gap) * 1e-6);
    r.max_publish_gap_ms = std::max(r.max_publish_gap_ms, static_cast<double>(pub_gap) * 1e-6);
    if (cam_gap > stale_ns) {
      ++r.camera_gaps_over_stale;
      r.long_gaps.push_back({{"sensor_id", f.sensor},
                             {"after_camera_timestamp_ns", it->second.first},
                             {"camera_gap_ms", static_cast<double>(cam_gap) * 1e-6},
                             {"publish_gap_ms", static_cast<double>(pub_gap) * 1e-6}});
    }
    if (pub_gap > stale_ns) ++r.publish_gaps_over_stale;
    it->second = {f.camera_ns, f.publish_ns};
  }
}

// Publish -> hand_node received, control, and camera -> command sent, of the commands in the
// window; camera -> command sent of every answer over the whole run (as the rig counts).
void command_stages(const Decoded& d, const Window& w, PipelineResult& r) {
  std::vector<double> pub_recv;
  std::vector<double> control;
  std::vector<double> fresh;
  std::vector<double> all;
  std::vector<double> all_no_hold;
  std::map<FrameKey, bool> counted;
  for (const CommandInfo& c : d.commands) {
    if (!w.contains(c.send_ns) || c.answers.empty()) continue;
    ++r.commands;
    ++r.command_kinds[c.kind];
    const RefInfo* newest = nullptr;
    for (const RefInfo& a : c.answers) {
      if (a.camera_ns > 0) all.push_back(static_cast<double>(c.send_ns - a.camera_ns) * 1e-6);
      if (a.camera_ns > 0 && c.kind != "hold" && c.kind != "stop")
        all_no_hold.push_back(static_cast<double>(c.send_ns - a.camera_ns) * 1e-6);
      if (a.hand_receive_ns > 0 &&
          (newest == nullptr || a.hand_receive_ns > newest->hand_receive_ns))
        newest = &a;
      const auto f = d.frames.find({a.sensor, a.sequence});
      if (a.hand_receive_ns > 0 && f != d.frames.end() && !counted[{a.sensor, a.sequence}]) {
        counted[{a.sensor, a.sequence}] = true;
        pub_recv.push_back(static_cast<double>(a.hand_receive_ns - f->second.publish_ns) * 1e-6);
      }
    }
    if (newest != nullptr) {
      control.push_back(static_cast<double>(c.send_ns - newest->hand_receive_ns) * 1e-6);
      fresh.push_back(static_cast<double>(c.send_ns - newest->camera_ns) * 1e-6);
    }
  }
  std::vector<double> all_run;
  for (const CommandInfo& c : d.commands) {
    for (const RefInfo& a : c.answers) {
      if (a.camera_ns > 0) all_run.push_back(static_cast<double>(c.send_ns - a.camera_ns) * 1e-6);
    }
  }
  r.cam_to_send_all_run = dist(all_run);
  r.e2e.n = all_run.size();  // the rig takes one sample per answer of every command it received
  r.pub_recv = dist(pub_recv);
  r.control = dist(control);
  r.cam_to_send_fresh = dist(fresh);
  r.cam_to_send_all = dist(all);
  r.cam_to_send_all_no_hold = dist(all_no_hold);
  r.cam_to_send_fresh_samples = fresh;
}

// Camera -> decided and hand_node received -> decided, per whole frame of the window (its
// camera timestamp in it), from the Decisions: every frame, not only those a command answers.
void decision_stages(const Decoded& d, const Window& w, PipelineResult& r) {
  std::vector<double> cam;
  std::vector<double> recv;
  std::set<FrameKey> decided;
  for (const DecisionInfo& di : d.decisions) {
    bool in_window = false;
    for (const RefInfo& a : di.answers) {
      const auto f = d.frames.find({a.sensor, a.sequence});
      if (f == d.frames.end() || !whole_in_window(f->second, w)) continue;
      in_window = true;
      if (!decided.insert({a.sensor, a.sequence}).second) continue;
      cam.push_back(static_cast<double>(di.time_ns - a.camera_ns) * 1e-6);
      if (a.hand_receive_ns > 0)
        recv.push_back(static_cast<double>(di.time_ns - a.hand_receive_ns) * 1e-6);
    }
    if (in_window) ++r.decisions;
  }
  for (const auto& [key, f] : d.frames) {
    if (whole_in_window(f, w) && !decided.count(key)) ++r.frames_without_decision;
  }
  r.cam_to_decision = dist(cam);
  r.receive_to_decision = dist(recv);
}

// A true slip episode of a fingertip starts where some element slides after a frame with none.
bool episode_starts(const std::vector<std::pair<std::int64_t, bool>>& tr, std::size_t k) {
  return tr[k].second && (k == 0 || !tr[k - 1].second);
}

std::uint64_t true_slip_episodes(const SlipTruth& truth) {
  std::uint64_t n = 0;
  for (const auto& [tip, tr] : truth) {
    for (std::size_t k = 0; k < tr.size(); ++k) {
      if (episode_starts(tr, k)) ++n;
    }
  }
  return n;
}

// The command hand_node sent just before the event in the same step: the last one before it with
// the same answers.
const CommandInfo* command_of(const v1::Event& e, const std::vector<CommandInfo>& commands) {
  const CommandInfo* cmd = nullptr;
  for (const CommandInfo& c : commands) {
    if (c.send_ns > e.time_ns()) break;
    bool same = c.answers.size() == static_cast<std::size_t>(e.answers_size());
    for (std::size_t i = 0; same && i < c.answers.size(); ++i)
      same = c.answers[i].camera_ns == e.answers(static_cast<int>(i)).camera_timestamp_ns();
    if (same) cmd = &c;
  }
  return cmd;
}

// One re-compression against the truth: the episode onsets of its fingertip nearest before and
// after the frame it answered.
struct Recompression {
  std::int64_t answered = 0;  // camera timestamp of the answered frame of its fingertip
  const CommandInfo* command = nullptr;
  std::int64_t onset = 0;  // 0: none
  std::int64_t onset_after = 0;
};

Recompression match_recompression(const v1::Event& e, const std::vector<CommandInfo>& commands,
                                  const std::vector<std::pair<std::int64_t, bool>>& tr) {
  Recompression m;
  for (const v1::FrameRef& a : e.answers()) {
    if (a.sensor_id() == e.sensor_id()) m.answered = a.camera_timestamp_ns();
  }
  m.command = command_of(e, commands);
  for (std::size_t k = 0; k < tr.size() && tr[k].first <= m.answered; ++k) {
    if (episode_starts(tr, k)) m.onset = tr[k].first;
  }
  for (std::size_t k = 1; k < tr.size(); ++k) {
    if (tr[k].first > m.answered && episode_starts(tr, k)) {
      m.onset_after = tr[k].first;
      break;
    }
  }
  return m;
}

// What happened around a re-compression, for the JSON.
json recompression_detail(const v1::Event& e, const Recompression& m,
                          const std::vector<std::pair<std::int64_t, bool>>& tr) {
  const auto rel = [&](std::int64_t t) {
    return t == 0 ? json(nullptr) : json(static_cast<double>(t - m.answered) * 1e-6);
  };
  return {{"sensor_id", e.sensor_id()},
          {"answered_camera_timestamp_ns", m.answered},
          {"command_sent_ms_after_answered", m.command ? rel(m.command->send_ns) : json(nullptr)},
          {"true_onset_before_ms", rel(m.onset)},
          {"true_onset_after_ms", rel(m.onset_after)},
          {"sliding_in_answered_frame", [&] {
             for (const auto& [t, sl] : tr) {
               if (t == m.answered) return json(sl);
             }
             return json(nullptr);
           }()}};
}

// Slip onset -> re-compress command, over the whole run: a RECOMPRESS event names the frames it
// answers; its command is the one hand_node sent just before it in the same step (same answers).
// The onset is the start of the fingertip's true slip episode nearest the answered frame, within
// three frame periods either side: the measurement may see a slip a frame before the truth calls
// it one, and then the time is negative.
void slip_to_recompress(Decoded& d, double fps, PipelineResult& r) {
  const auto near_ns = static_cast<std::int64_t>(3e9 / fps) + 1'000'000;
  for (const v1::Event& e : d.recompress) {
    ++r.recompress_events;
    const auto& tr = d.truth[e.sensor_id()];
    const Recompression m = match_recompression(e, d.commands, tr);
    r.recompress_detail.push_back(recompression_detail(e, m, tr));
    if (m.command == nullptr || m.answered == 0) {
      ++r.recompress_no_command;
      continue;
    }
    std::int64_t nearest = 0;
    for (const std::int64_t o : {m.onset, m.onset_after}) {
      if (o != 0 && std::llabs(o - m.answered) <= near_ns &&
          (nearest == 0 || std::llabs(o - m.answered) < std::llabs(nearest - m.answered)))
        nearest = o;
    }
    if (nearest == 0) {
      ++r.recompress_no_onset;
      continue;
    }
    r.slip_to_recompress_ms.push_back(static_cast<double>(m.command->send_ns - nearest) * 1e-6);
  }
}

}  // namespace

double percentile(const std::vector<double>& v, double q) {
  return util::nearest_rank_percentile(v, q, std::nan(""));
}

Dist dist(const std::vector<double>& v) {
  Dist d;
  d.n = v.size();
  if (v.empty()) return d;
  d.p50 = percentile(v, 0.50);
  d.p99 = percentile(v, 0.99);
  d.max = *std::max_element(v.begin(), v.end());
  return d;
}

Dist later_of_pair(const std::vector<std::pair<std::int64_t, std::int64_t>>& camera_receive_ns) {
  std::map<std::int64_t, std::pair<int, std::int64_t>> by_exposure;  // frames seen, latest
  for (const auto& [camera_ns, receive_ns] : camera_receive_ns) {
    auto& [count, latest] = by_exposure[camera_ns];
    latest = count == 0 ? receive_ns : std::max(latest, receive_ns);
    ++count;
  }
  std::vector<double> v;
  for (const auto& [camera_ns, e] : by_exposure) {
    if (e.first == 2) v.push_back(static_cast<double>(e.second - camera_ns) * 1e-6);
  }
  return dist(v);
}

json to_json(const Dist& d) {
  const auto num = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  return {{"n", d.n}, {"p50_ms", num(d.p50)}, {"p99_ms", num(d.p99)}, {"max_ms", num(d.max)}};
}

std::string ms(double x, int digits) {
  return std::isfinite(x) ? fmt::format("{:.{}f}", x, digits) : std::string("-");
}

void analyse_capture(const std::vector<Captured>& cap, const Window& w, double fps,
                     PipelineResult& r) {
  Decoded d = decode_captured(cap, w, r);
  frame_stages(d.frames, w, r);
  frame_gaps(d.frames, w, fps, r);
  command_stages(d, w, r);
  decision_stages(d, w, r);
  r.true_slip_episodes = true_slip_episodes(d.truth);
  slip_to_recompress(d, fps, r);
}

void write_capture(const std::filesystem::path& path, const std::vector<Captured>& cap,
                   const std::string& note) {
  v1::LogHeader header;
  header.set_writer("tactile_system_latency_bench");
  header.set_note(note);
  recording::LogWriterOptions options;
  options.overwrite = true;
  recording::LogWriter out(path, header, options);
  for (const Captured& c : cap) {
    if (out.append(c.receive_ns, c.topic, "", v1::PAYLOAD_KIND_ENVELOPE, c.payload) !=
        recording::WriteStatus::kOk)
      throw std::runtime_error(fmt::format("{}: {}", path.string(), out.error()));
  }
  if (out.close() != recording::WriteStatus::kOk)
    throw std::runtime_error(fmt::format("{}: {}", path.string(), out.error()));
}

std::vector<Captured> read_capture(const std::filesystem::path& path) {
  recording::LogReader in(path);
  std::vector<Captured> cap;
  v1::LogRecord record;
  recording::ReadStatus status;
  while ((status = in.next(record)) == recording::ReadStatus::kRecord) {
    const std::string& p = record.payload();
    cap.push_back(
        {record.receive_time_ns(), record.topic(), std::vector<std::uint8_t>(p.begin(), p.end())});
  }
  if (status != recording::ReadStatus::kEnd) throw std::runtime_error(in.problem());
  return cap;
}

}  // namespace tactile::bench
