#include "latency_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <regex>

namespace tactile::bench {

// The IP packets (bytes) a camera sends for one frame of `image_bytes` at GVSP packet size
// `packet_size`: a leader, the image in data packets (IPv4 20, UDP 8 and GVSP 8 bytes of each
// are headers) and a trailer (about 48 bytes of GVSP payload each) - the arithmetic of
// bench/system/gige_link_report.py.
constexpr std::size_t kGvspIpUdpHeaders = 36;
std::vector<std::size_t> gvsp_frame_packets(std::size_t image_bytes, std::size_t packet_size) {
  constexpr std::size_t kLeaderTrailer = kGvspIpUdpHeaders + 48;
  const std::size_t per_packet = packet_size - kGvspIpUdpHeaders;
  std::vector<std::size_t> packets{kLeaderTrailer};
  for (std::size_t left = image_bytes; left > 0; left -= std::min(left, per_packet))
    packets.push_back(kGvspIpUdpHeaders + std::min(left, per_packet));
  packets.push_back(kLeaderTrailer);
  return packets;
}

// The transport alone, p50: an exposure's two frames through Aravis (the later of the two: the
// controller answers both), then one ZeroMQ round trip. NaN when either was not measured.
double transport_alone_p50(const RateResult& rr) {
  if (!rr.aravis || !rr.zmq) return std::nan("");
  return rr.aravis->latency_pair.p50 + rr.zmq->round_trip.p50;
}

// The same with the p50 over single frames of either camera (this benchmark's figure before the
// pair): below the pair's by the time one camera's frame waits for the other's.
double transport_alone_per_frame_p50(const RateResult& rr) {
  if (!rr.aravis || !rr.zmq) return std::nan("");
  return rr.aravis->latency.p50 + rr.zmq->round_trip.p50;
}

// The link's rate in bit/s from tc's form (1gbit, 500mbit, 100kbit).
double rate_bps(const std::string& rate) {
  std::smatch m;
  if (!std::regex_match(rate, m, std::regex("([1-9][0-9]*)(kbit|mbit|gbit)"))) return std::nan("");
  const double unit = m[2] == "kbit" ? 1e3 : m[2] == "mbit" ? 1e6 : 1e9;
  return std::stod(m[1]) * unit;
}

// The time a frame of `image_bytes` takes on the link: its GVSP packets (gvsp_frame_packets),
// each with 38 bytes of Ethernet around it (header 14, FCS 4, preamble 8, inter-frame gap 12).
// In ms.
double wire_time_ms(std::size_t image_bytes, int packet_size, double bps) {
  constexpr std::size_t kEthernet = 38;
  std::size_t bytes = 0;
  for (const std::size_t ip :
       gvsp_frame_packets(image_bytes, static_cast<std::size_t>(packet_size)))
    bytes += ip + kEthernet;
  return static_cast<double>(bytes) * 8.0 / bps * 1e3;
}

// The wire time of the frames a run's transport alone received (the region's size), at the
// link's MTU and rate; NaN when it received none.
double frame_wire_ms(const RateResult& rr, const Settings& s) {
  const std::size_t bytes = rr.aravis ? rr.aravis->frame_bytes : 0;
  return bytes > 0 ? wire_time_ms(bytes, s.link_mtu, rate_bps(s.link_rate)) : std::nan("");
}

// The transport a decision waits for, p50: an exposure's two frames through Aravis (the later of
// the two), then ZeroMQ's PUB -> SUB to hand_node. NaN when either was not measured.
double transport_to_decision_p50(const RateResult& rr) {
  if (!rr.aravis || !rr.zmq) return std::nan("");
  return rr.aravis->latency_pair.p50 + rr.zmq->pub_sub.p50;
}

json link_json(const LinkCounters& c) {
  if (!c.known) return nullptr;
  return {{"burst", c.burst},
          {"bytes", c.bytes},
          {"packets", c.packets},
          {"dropped", c.dropped},
          {"overlimits", c.overlimits}};
}

json result_json(const RateResult& rr) {
  const PipelineResult& p = rr.pipe;
  json j;
  j["fps"] = p.fps;
  j["roi"] = rr.roi;
  j["run"] = rr.run;
  j["cameras"] = 2;
  j["window_s"] = p.window_s;
  j["task_ended_early"] = p.task_ended_early;
  j["load_average_at_start"] = p.load_at_start;
  j["host_steal_ms_in_window"] = p.steal_ms;
  j["io_full_stall_ms_in_window"] = p.io_stall_ms;
  j["stall_probe"] = {{"sched_fifo", p.probe_fifo},
                      {"max_late_ms", p.probe_max_late_ms},
                      {"max_late_at_ns", p.probe_max_at_ns},
                      {"wakeups_over_10ms_late", p.probe_stalls}};
  j["major_page_faults_in_window"] = p.major_faults;
  j["benchmark_subscriber_sched_idle"] = p.subscriber_idle;
  j["end_to_end_rig_report"] = to_json(p.e2e);
  j["gige_received_before_camera_timestamp"] = p.gige_negative;
  j["stages"] = {
      {"gige_receive", to_json(p.gige)},
      {"gige_receive_later_of_pair", to_json(p.gige_pair)},
      {"measure_and_publish", to_json(p.measure)},
      {"measurement_core", to_json(p.measure_core)},
      {"publish_to_hand_receive", to_json(p.pub_recv)},
      {"control", to_json(p.control)},
      {"camera_to_command_sent_freshest", to_json(p.cam_to_send_fresh)},
      {"camera_to_command_sent_all_answers", to_json(p.cam_to_send_all)},
      {"camera_to_command_sent_all_answers_without_hold_stop", to_json(p.cam_to_send_all_no_hold)},
      {"camera_to_decision_every_frame", to_json(p.cam_to_decision)},
      {"hand_receive_to_decision_every_frame", to_json(p.receive_to_decision)}};
  j["decisions"] = {{"in_window", p.decisions},
                    {"whole_frames_without_decision", p.frames_without_decision}};
  j["command_kinds_in_window"] = p.command_kinds;
  j["frames"] = {{"published", p.frames},
                 {"complete", p.frames_complete},
                 {"incomplete", p.frames_incomplete},
                 {"camera_frames_lost", p.frames_skipped},
                 {"missed_by_benchmark", p.sequence_gaps},
                 {"commands", p.commands},
                 {"tactile_frame_bytes_p50", p.frame_bytes_p50},
                 {"arm_command_bytes_p50", p.command_bytes_p50}};
  j["cpu_percent_of_one_core"] = p.cpu;
  j["slip_onset_to_recompress_command_sent"] = to_json(dist(p.slip_to_recompress_ms));
  j["slip_onset_to_recompress_samples_ms"] = p.slip_to_recompress_ms;
  j["recompress_events"] = p.recompress_events;
  j["recompress_without_command"] = p.recompress_no_command;
  j["recompress_without_true_onset_within_3_periods"] = p.recompress_no_onset;
  j["true_slip_episodes"] = p.true_slip_episodes;
  j["recompress_detail"] = p.recompress_detail;
  j["incomplete_frames_whole_run"] = p.incomplete_run;
  j["frame_gaps"] = {{"max_camera_timestamp_gap_ms", p.max_camera_gap_ms},
                     {"max_publish_gap_ms", p.max_publish_gap_ms},
                     {"camera_gaps_over_3_periods", p.camera_gaps_over_stale},
                     {"publish_gaps_over_3_periods", p.publish_gaps_over_stale},
                     {"camera_gaps_over_3_periods_list", p.long_gaps}};
  j["camera_to_command_sent_all_answers_whole_run"] = to_json(p.cam_to_send_all_run);
  j["events"] = p.events;
  j["rig_report"] = p.report;
  j["rig_counters"] = p.rig_counters;
  j["camera_link"] = link_json(p.link);
  if (rr.aravis) {
    const AravisResult& a = *rr.aravis;
    j["transport"]["aravis_receive"] = to_json(a.latency);
    j["transport"]["aravis_receive_later_of_pair"] = to_json(a.latency_pair);
    j["transport"]["aravis_host_steal_ms"] = a.steal_ms;
    j["transport"]["aravis_received_before_camera_timestamp"] = a.negative;
    j["transport"]["aravis_frames"] = {
        {"received", a.frames}, {"complete", a.complete}, {"lost", a.lost}};
    j["transport"]["aravis_receiver_cpu_percent"] = a.receiver_cpu;
    j["transport"]["aravis_rig_cpu_percent"] = a.rig_cpu;
    j["transport"]["aravis_frame_image_bytes"] = a.frame_bytes;
    j["transport"]["camera_link"] = link_json(a.link);
    j["link_alone"] = {{"packets", a.link_alone_packets},
                       {"send_to_last_received", to_json(a.link_alone)}};
    for (const Region& g : a.regions) {
      j["transport"]["aravis_regions"].push_back(
          g.width > 0 ? json{{"x", g.x}, {"y", g.y}, {"width", g.width}, {"height", g.height}}
                      : json("whole frames"));
    }
  }
  if (rr.zmq) {
    const ZmqResult& z = *rr.zmq;
    j["transport"]["zmq_round_trip"] = to_json(z.round_trip);
    j["transport"]["zmq_pub_sub"] = to_json(z.pub_sub);
    j["transport"]["zmq_dealer_router"] = to_json(z.dealer_router);
    j["transport"]["zmq_bytes"] = {{"out", z.frame_bytes}, {"back", z.command_bytes}};
    j["transport"]["zmq_sent"] = z.sent;
    j["transport"]["zmq_answered"] = z.answered;
  }
  if (rr.aravis && rr.zmq) {
    const double t = transport_alone_p50(rr);
    const double t1 = transport_alone_per_frame_p50(rr);
    j["transport"]["alone_p50_ms"] = t;
    j["transport"]["alone_per_frame_p50_ms"] = t1;
    j["pipeline_added_p50_ms"] = p.e2e.p50 - t;
    j["pipeline_over_transport_p50"] = p.e2e.p50 / t;
    j["pipeline_added_over_per_frame_transport_p50_ms"] = p.e2e.p50 - t1;
    j["transport"]["to_decision_p50_ms"] = transport_to_decision_p50(rr);
    j["decision_added_p50_ms"] = p.cam_to_decision.p50 - transport_to_decision_p50(rr);
  }
  return j;
}

// With several runs per rate: each run's p50 figures and their median, the added target judged on
// the median (one run's end to end rests on a few dozen answers and moves by tens of
// microseconds from run to run).
void print_runs_summary(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nRuns per rate: %d. p50 figures of each run, then their median (ms):\n\n| fps | e2e p50 | "
      "transport alone p50 | added p50 | (added over the per-frame transport) | runs with "
      "added <= 0.150 |\n|---|---|---|---|---|---|\n",
      s.runs);
  std::map<std::pair<double, std::string>, std::vector<const RateResult*>> by_rate;
  for (const RateResult& rr : rs)
    by_rate[{rr.pipe.fps, rr.roi}].push_back(&rr);
  for (const auto& [key, runs] : by_rate) {
    std::vector<double> e2e, alone, added, added1;
    std::string e2e_s, alone_s, added_s, added1_s;
    int met = 0;
    for (const RateResult* rr : runs) {
      const double t = transport_alone_p50(*rr);
      const double t1 = transport_alone_per_frame_p50(*rr);
      const double a = rr->pipe.e2e.p50 - t;
      e2e.push_back(rr->pipe.e2e.p50);
      alone.push_back(t);
      added.push_back(a);
      added1.push_back(rr->pipe.e2e.p50 - t1);
      met += std::isfinite(a) && a <= 0.150 ? 1 : 0;
      const char* sep = e2e_s.empty() ? "" : ", ";
      e2e_s += sep + ms(rr->pipe.e2e.p50);
      alone_s += sep + ms(t);
      added_s += sep + ms(a);
      added1_s += sep + ms(rr->pipe.e2e.p50 - t1);
    }
    std::printf("| %s | %s: **%s** | %s: **%s** | %s: **%s** | %s: **%s** | %d of %zu |\n",
                s.rois.size() > 1 ? fmt::format("{:.0f}, roi {}", key.first, key.second).c_str()
                                  : fmt::format("{:.0f}", key.first).c_str(),
                e2e_s.c_str(), ms(percentile(e2e, 0.5)).c_str(), alone_s.c_str(),
                ms(percentile(alone, 0.5)).c_str(), added_s.c_str(),
                ms(percentile(added, 0.5)).c_str(), added1_s.c_str(),
                ms(percentile(added1, 0.5)).c_str(), met, runs.size());
  }
}

// A table row's first cell: the rate, the region when several were run, and the run when there
// are several.
std::string row_label(const RateResult& rr, const Settings& s) {
  std::string label = fmt::format("{:.0f}", rr.pipe.fps);
  if (s.rois.size() > 1) label += ", roi " + rr.roi;
  if (s.runs > 1) label += fmt::format(" #{}", rr.run);
  return label;
}

// What was run, and per rate: end to end against the transport alone, and CPU.
void print_overview(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nTwo cameras, %.0f s measured per rate after the task started (+%.0f s warm-up); "
      "transport alone %.0f s per rate. Times in ms; CPU in %% of one core.%s\n\n",
      s.seconds, s.warmup_s, s.transport_seconds,
      s.realtime_priority > 0
          ? fmt::format(" sensor_node, hand_node and the transport alone's ends under SCHED_FIFO "
                        "{} (--realtime-priority).",
                        s.realtime_priority)
                .c_str()
          : "");
  std::printf(
      "| fps | e2e p50 | e2e p99 | e2e max | transport alone p50 | added p50 | ratio | "
      "(added over the per-frame transport) | incomplete | frames | sensor_node CPU | hand_node "
      "CPU | rig CPU | benchmark CPU |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    const double t = transport_alone_p50(rr);
    const auto cpu = [&](const char* k) {
      return p.cpu.count(k) ? fmt::format("{:.1f} %", p.cpu.at(k)) : std::string("-");
    };
    std::printf("| %s | %s | %s | %s | %s | %s | %s | %s | %llu | %llu | %s | %s | %s | %s |\n",
                row_label(rr, s).c_str(), ms(p.e2e.p50).c_str(), ms(p.e2e.p99).c_str(),
                ms(p.e2e.max).c_str(), ms(t).c_str(), ms(p.e2e.p50 - t).c_str(),
                std::isfinite(t) ? fmt::format("{:.2f}", p.e2e.p50 / t).c_str() : "-",
                ms(p.e2e.p50 - transport_alone_per_frame_p50(rr)).c_str(),
                static_cast<unsigned long long>(p.frames_incomplete),
                static_cast<unsigned long long>(p.frames), cpu("sensor_node").c_str(),
                cpu("hand_node").c_str(), cpu("rig").c_str(), cpu("benchmark").c_str());
  }
}

// Frames, faults and the machine's own pauses in the window.
void print_frames_table(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nFrames and faults in the window (e2e samples: whole run, one per answer of every "
      "command):\n\n"
      "| fps | window s | TactileFrames | complete | incomplete | camera frames lost | missed by "
      "the benchmark | gaps > 3 periods, camera / publish (max ms) | commands | e2e samples | "
      "STALE_HOLD events (run) | host steal ms | all tasks stalled on I/O, ms | major page faults, "
      "sensor_node / hand_node / rig | stall probe: latest wake-up ms (> 10 ms) | rig |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    const auto stale = p.events.find("EVENT_KIND_STALE_HOLD");
    const auto fault = [&](const char* k) {
      return p.major_faults.count(k) ? fmt::format("{:.0f}", p.major_faults.at(k))
                                     : std::string("-");
    };
    const std::string faults =
        fault("sensor_node") + " / " + fault("hand_node") + " / " + fault("rig");
    std::printf(
        "| %s | %.1f | %llu | %llu | %llu | %llu | %llu | %llu / %llu (%.1f / %.1f) | %llu | %zu "
        "| %llu | %.0f | %.1f | %s | %.1f (%llu)%s | %s |\n",
        row_label(rr, s).c_str(), p.window_s, static_cast<unsigned long long>(p.frames),
        static_cast<unsigned long long>(p.frames_complete),
        static_cast<unsigned long long>(p.frames_incomplete),
        static_cast<unsigned long long>(p.frames_skipped),
        static_cast<unsigned long long>(p.sequence_gaps),
        static_cast<unsigned long long>(p.camera_gaps_over_stale),
        static_cast<unsigned long long>(p.publish_gaps_over_stale), p.max_camera_gap_ms,
        p.max_publish_gap_ms, static_cast<unsigned long long>(p.commands), p.e2e.n,
        static_cast<unsigned long long>(stale == p.events.end() ? 0 : stale->second), p.steal_ms,
        p.io_stall_ms, faults.c_str(), p.probe_max_late_ms,
        static_cast<unsigned long long>(p.probe_stalls), p.probe_fifo ? "" : " (not FIFO)",
        p.rig_counters.c_str());
  }
}

// Each stage of the pipeline, camera to command.
void print_stages_table(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nStages, p50 / p99 (ms):\n\n"
      "| fps | GigE Vision receive | (later of the exposure's two) | measurement + publish | (core "
      "alone) | publish -> hand_node receive | control | camera -> command sent (freshest) | "
      "camera -> command sent (all answers) | (all answers, Hold/Stop apart) | commands (holds) "
      "|\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    const auto pp = [](const Dist& d) { return ms(d.p50) + " / " + ms(d.p99); };
    const auto holds = p.command_kinds.find("hold");
    std::printf(
        "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %llu (%llu) |\n",
        row_label(rr, s).c_str(), pp(p.gige).c_str(), pp(p.gige_pair).c_str(),
        pp(p.measure).c_str(), pp(p.measure_core).c_str(), pp(p.pub_recv).c_str(),
        pp(p.control).c_str(), pp(p.cam_to_send_fresh).c_str(), pp(p.cam_to_send_all).c_str(),
        pp(p.cam_to_send_all_no_hold).c_str(), static_cast<unsigned long long>(p.commands),
        static_cast<unsigned long long>(holds == p.command_kinds.end() ? 0 : holds->second));
  }
}

// Every whole frame's decision (hand_node's Decisions): thousands of samples where the commands
// give a few dozen, and what the pipeline adds to the transport a decision waits for.
void print_decisions_table(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nEvery frame's decision (camera timestamp -> hand_node's decision on it; window), ms:\n\n"
      "| fps | frames decided | whole frames without a decision | camera -> decision p50 / p99 / "
      "max | hand_node receive -> decision p50 / p99 | transport alone to a decision p50 (Aravis, "
      "later of two, + PUB -> SUB) | added p50 | ratio |\n|---|---|---|---|---|---|---|---|\n");
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    const double t = transport_to_decision_p50(rr);
    std::printf(
        "| %s | %zu | %llu | %s / %s / %s | %s / %s | %s | %s | %s |\n", row_label(rr, s).c_str(),
        p.cam_to_decision.n, static_cast<unsigned long long>(p.frames_without_decision),
        ms(p.cam_to_decision.p50).c_str(), ms(p.cam_to_decision.p99).c_str(),
        ms(p.cam_to_decision.max).c_str(), ms(p.receive_to_decision.p50).c_str(),
        ms(p.receive_to_decision.p99).c_str(), ms(t).c_str(), ms(p.cam_to_decision.p50 - t).c_str(),
        std::isfinite(t) ? fmt::format("{:.2f}", p.cam_to_decision.p50 / t).c_str() : "-");
  }
}

const char* verdict(bool measured, bool ok) {
  return !measured ? "not measured" : ok ? "met" : "NOT met";
}

// The cameras' link (shaped links only): what a frame takes on it and what the runs put through.
void print_link_table(const std::vector<RateResult>& rs, const Settings& s) {
  if (s.camera_link == "loopback") return;
  const bool shared = s.camera_link == "shared";
  std::printf(
      "\nCamera link: %s (%s), %s, MTU %d, tbf burst %d bytes, queue 1,000,000 bytes:\n\n"
      "| fps | frame (image bytes) | wire time of a frame, ms | what an exposure waits for "
      "(computed) | the link alone: an exposure's packets, send -> last received p50 / p99 | "
      "link load needed | pipeline: packets, dropped, over the rate | transport alone: packets, "
      "dropped, over the rate |\n|---|---|---|---|---|---|---|---|\n",
      s.camera_link.c_str(), shared ? "both cameras on one link" : "one link per camera",
      s.link_rate.c_str(), s.link_mtu, rs.empty() ? 0 : rs.front().pipe.link.burst);
  for (const RateResult& rr : rs) {
    const std::size_t bytes = rr.aravis ? rr.aravis->frame_bytes : 0;
    const double wire = frame_wire_ms(rr, s);
    // On a shared link the later of an exposure's two frames waits for both.
    const double pair = shared ? 2 * wire : wire;
    const double load = wire * 1e-3 * rr.pipe.fps * (shared ? 2 : 1);
    const auto counters = [](const LinkCounters& c) {
      return c.known ? fmt::format("{}, {}, {}", c.packets, c.dropped, c.overlimits)
                     : std::string("-");
    };
    const Dist alone = rr.aravis ? rr.aravis->link_alone : Dist{};
    std::printf("| %s | %zu | %s | %s | %s | %s | %s | %s |\n", row_label(rr, s).c_str(), bytes,
                ms(wire, 2).c_str(), ms(pair, 2).c_str(),
                alone.n > 0 ? fmt::format("{} packets: {} / {}", rr.aravis->link_alone_packets,
                                          ms(alone.p50, 2), ms(alone.p99, 2))
                                  .c_str()
                            : "-",
                std::isfinite(load) ? fmt::format("{:.0f} %", load * 100).c_str() : "-",
                counters(rr.pipe.link).c_str(),
                rr.aravis ? counters(rr.aravis->link).c_str() : "-");
  }
  // Issue 21's targets: on a shared link, exposure -> command p99 at most the wire time of the
  // two frames the command waits for + 0.5 ms; on a link each, p50 at most one frame's + 0.3 ms.
  std::printf(
      "\nTargets on the link (%s): %s\n\n| fps | bound, ms | exposure -> command (rig, "
      "answers) p50 / p99 | exposure -> decision (every frame) p50 / p99 | transport alone to a "
      "decision p50 | the link alone p50 | verdict (command / decision) |\n"
      "|---|---|---|---|---|---|---|\n",
      s.camera_link.c_str(),
      shared ? "p99 <= wire time of the two frames + 0.5 ms"
             : "p50 <= wire time of the frame + 0.3 ms");
  for (const RateResult& rr : rs) {
    const double wire = frame_wire_ms(rr, s);
    const double bound = shared ? 2 * wire + 0.5 : wire + 0.3;
    const PipelineResult& p = rr.pipe;
    const double cmd = shared ? p.e2e.p99 : p.e2e.p50;
    const double dec = shared ? p.cam_to_decision.p99 : p.cam_to_decision.p50;
    std::printf("| %s | %s | %s / %s | %s / %s | %s | %s | %s / %s |\n", row_label(rr, s).c_str(),
                ms(bound, 2).c_str(), ms(p.e2e.p50).c_str(), ms(p.e2e.p99).c_str(),
                ms(p.cam_to_decision.p50).c_str(), ms(p.cam_to_decision.p99).c_str(),
                ms(transport_to_decision_p50(rr)).c_str(),
                rr.aravis ? ms(rr.aravis->link_alone.p50).c_str() : "-",
                verdict(std::isfinite(cmd) && std::isfinite(bound), cmd <= bound),
                verdict(std::isfinite(dec) && std::isfinite(bound), dec <= bound));
  }
}

// The transport alone: Aravis receive and the ZeroMQ hops.
void print_transport_table(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nTransport alone, p50 / p99 / max (ms):\n\n"
      "| fps | Aravis receive | (later of the exposure's two) | frames (complete/received) | "
      "receiver CPU | host steal ms | ZeroMQ round trip | PUB -> SUB | DEALER -> ROUTER | bytes "
      "out/back |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RateResult& rr : rs) {
    if (!rr.aravis || !rr.zmq) continue;
    const auto ppm = [](const Dist& d) {
      return ms(d.p50) + " / " + ms(d.p99) + " / " + ms(d.max);
    };
    const AravisResult& a = *rr.aravis;
    const ZmqResult& z = *rr.zmq;
    std::printf("| %s | %s | %s | %llu/%llu | %.1f %% | %.0f | %s | %s | %s | %zu/%zu |\n",
                row_label(rr, s).c_str(), ppm(a.latency).c_str(), ppm(a.latency_pair).c_str(),
                static_cast<unsigned long long>(a.complete),
                static_cast<unsigned long long>(a.frames), a.receiver_cpu, a.steal_ms,
                ppm(z.round_trip).c_str(), ppm(z.pub_sub).c_str(), ppm(z.dealer_router).c_str(),
                z.frame_bytes, z.command_bytes);
  }
}

// Slip onset (ground truth) -> re-compress command.
void print_slip_table(const std::vector<RateResult>& rs, const Settings& s) {
  std::printf(
      "\nSlip onset (ground truth) -> re-compress command sent by hand_node, whole run:\n\n"
      "| fps | true slip episodes | re-compressions | with a true onset within 3 periods | without "
      "| min | p50 | max | 2 periods + 1 ms |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    const Dist d = dist(p.slip_to_recompress_ms);
    const double lo =
        p.slip_to_recompress_ms.empty()
            ? std::nan("")
            : *std::min_element(p.slip_to_recompress_ms.begin(), p.slip_to_recompress_ms.end());
    std::printf("| %s | %llu | %llu | %zu | %llu | %s | %s | %s | %.1f |\n",
                row_label(rr, s).c_str(), static_cast<unsigned long long>(p.true_slip_episodes),
                static_cast<unsigned long long>(p.recompress_events), d.n,
                static_cast<unsigned long long>(p.recompress_no_onset + p.recompress_no_command),
                ms(lo, 2).c_str(), ms(d.p50, 2).c_str(), ms(d.max, 2).c_str(),
                2000.0 / p.fps + 1.0);
  }
}

// Frames that arrived before their camera timestamp make the latencies at that rate suspect.
void print_timestamp_warnings(const std::vector<RateResult>& rs, const Settings& s) {
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    const std::uint64_t ahead = p.gige_negative + (rr.aravis ? rr.aravis->negative : 0);
    const double total = static_cast<double>(p.gige.n + (rr.aravis ? rr.aravis->latency.n : 0));
    if (ahead > 0) {
      std::printf(
          "\nWARNING %s fps: %llu of %.0f frames (%.2f %%) arrived before their camera timestamp "
          "(pipeline %llu, transport alone %llu): the rig published those images earlier than "
          "their timestamps say (a late camera thread sends the newest image, rendered "
          "render_lead_s ahead; above 1/render_lead_s fps every image goes a period early). %s\n",
          row_label(rr, s).c_str(), static_cast<unsigned long long>(ahead), total,
          100.0 * static_cast<double>(ahead) / total,
          static_cast<unsigned long long>(p.gige_negative),
          static_cast<unsigned long long>(rr.aravis ? rr.aravis->negative : 0),
          static_cast<double>(ahead) > 0.01 * total
              ? "Latencies at this rate are NOT valid."
              : "Rare: latencies stand, their tails slightly understated.");
    }
  }
}

// Pauses of the machine (steal, stalled wake-ups, I/O, page faults) that explain tail latencies.
void print_machine_notes(const std::vector<RateResult>& rs, const Settings& s) {
  for (const RateResult& rr : rs) {
    const PipelineResult& p = rr.pipe;
    // One 10 ms tick of steal is common; more means the host paused this machine for a while.
    if (p.steal_ms > 10.0)
      std::printf(
          "\nNOTE %s fps: the host took %.0f ms of CPU time from this virtual machine during the "
          "window (steal): while it does, every process stalls at once, and a tail latency of that "
          "size is the machine's, not the pipeline's.\n",
          row_label(rr, s).c_str(), p.steal_ms);
    if (p.probe_stalls > 0)
      std::printf(
          "\nNOTE %s fps: a thread sleeping 1 ms at a time%s woke up to %.1f ms late (%llu times "
          "more than 10 ms): %s\n",
          row_label(rr, s).c_str(), p.probe_fifo ? " at real-time priority" : "",
          p.probe_max_late_ms, static_cast<unsigned long long>(p.probe_stalls),
          p.probe_fifo ? "nothing on this machine can delay it, so the machine itself did not run "
                         "(a pause by the host); a tail latency of that size is the machine's."
                       : "it ran at the normal policy, so the machine may have been busy.");
    if (p.io_stall_ms > 5.0)
      std::printf(
          "\nNOTE %s fps: every task of this machine waited for I/O at once for %.1f ms of the "
          "window (/proc/pressure/io): while they do, no process runs.\n",
          row_label(rr, s).c_str(), p.io_stall_ms);
    for (const char* k : {"sensor_node", "hand_node", "rig"}) {
      if (p.major_faults.count(k) && p.major_faults.at(k) > 0)
        std::printf(
            "\nNOTE %s fps: %s took %.0f major page faults in the window (pages the kernel had "
            "evicted, read back from disk while a thread waited).\n",
            row_label(rr, s).c_str(), k, p.major_faults.at(k));
    }
  }
}

// The targets, judged on one 200 fps run.
void print_targets(const RateResult& rr, const Settings& s) {
  const PipelineResult& p = rr.pipe;
  std::printf(
      "\nTargets (two cameras, 200 fps, roi %s%s):\n\n| target | measured | verdict "
      "|\n|---|---|---|\n",
      rr.roi.c_str(), s.runs > 1 ? fmt::format(", run {} of {}", rr.run, s.runs).c_str() : "");
  std::printf("| end to end p50 <= 1 ms | %s ms | %s |\n", ms(p.e2e.p50).c_str(),
              verdict(std::isfinite(p.e2e.p50), p.e2e.p50 <= 1.0));
  std::printf("| end to end p99 <= 3 ms (max reported) | %s ms (max %s ms) | %s |\n",
              ms(p.e2e.p99).c_str(), ms(p.e2e.max).c_str(),
              verdict(std::isfinite(p.e2e.p99), p.e2e.p99 <= 3.0));
  std::smatch m;
  long long rig_incomplete = -1;
  const std::regex re("incomplete ([0-9]+)");
  if (std::regex_search(p.rig_counters, m, re)) rig_incomplete = std::stoll(m[1].str());
  std::printf("| no incomplete frames | %llu in the window; %s in the whole run (rig) | %s |\n",
              static_cast<unsigned long long>(p.frames_incomplete),
              rig_incomplete < 0 ? "?" : std::to_string(rig_incomplete).c_str(),
              verdict(true, p.frames_incomplete == 0 && rig_incomplete == 0));
  if (rr.aravis && rr.zmq) {
    const double added = p.e2e.p50 - transport_alone_p50(rr);
    std::printf(
        "| pipeline adds <= 0.150 ms at p50 over the transport alone | %s ms (%s ms over the "
        "per-frame transport) | %s |\n",
        ms(added).c_str(), ms(p.e2e.p50 - transport_alone_per_frame_p50(rr)).c_str(),
        verdict(std::isfinite(added), added <= 0.150));
  }
  const bool cpu_known = p.cpu.count("sensor_node") > 0;
  std::printf("| sensor_node <= 25 %% of one core | %s | %s |\n",
              cpu_known ? fmt::format("{:.1f} %", p.cpu.at("sensor_node")).c_str() : "-",
              verdict(cpu_known, cpu_known && p.cpu.at("sensor_node") <= 25.0));
  const Dist d = dist(p.slip_to_recompress_ms);
  std::printf("| slip onset -> re-compress command <= 2 periods + 1 ms (%.1f ms) | %s | %s |\n",
              2000.0 / p.fps + 1.0,
              d.n > 0 ? fmt::format("max {} ms over {}", ms(d.max, 2), d.n).c_str()
                      : "no re-compression near a true onset",
              verdict(d.n > 0, d.max <= 2000.0 / p.fps + 1.0));
}

void print_tables(const std::vector<RateResult>& rs, const Settings& s) {
  print_overview(rs, s);
  print_frames_table(rs, s);
  print_stages_table(rs, s);
  print_decisions_table(rs, s);
  print_link_table(rs, s);
  print_transport_table(rs, s);
  print_slip_table(rs, s);
  print_timestamp_warnings(rs, s);
  print_machine_notes(rs, s);
  for (const RateResult& rr : rs) {
    if (std::abs(rr.pipe.fps - 200.0) > 1e-9) continue;
    print_targets(rr, s);
  }
  if (s.runs > 1) print_runs_summary(rs, s);
  std::fflush(stdout);
}

}  // namespace tactile::bench
