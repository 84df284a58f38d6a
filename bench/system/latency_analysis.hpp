#pragma once

// The latency benchmark's pure analysis (docs/benchmarks.md, "Latency and load"): what the
// benchmark's subscriber captured during a pipeline run (TactileFrames, ArmCommands, Decisions,
// events and the rig's ground truth, each with its receive time), decoded and turned into the
// stages' latency statistics, frame counts and gaps and slip onset -> re-compression times. No
// processes, sockets or clocks: the same capture gives the same figures, here and in the tests
// (tests/unit/bench, on a recorded capture). The capture is kept in the project's recording
// format (tactile-log/1, docs/recording.md).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tactile/v1/tactile.pb.h"

namespace tactile::bench {

using nlohmann::json;

// Nearest rank (util/percentile.hpp), as the rig's report computes its latency percentiles; NaN
// (printed "-") when there are no values.
double percentile(const std::vector<double>& v, double q);

// A latency distribution in ms: count, p50 and p99 by nearest rank, maximum (NaN when empty).
struct Dist {
  std::size_t n = 0;
  double p50 = std::nan("");
  double p99 = std::nan("");
  double max = std::nan("");
};

Dist dist(const std::vector<double>& v);

// The two cameras expose together, and the controller answers an exposure once both of its frames
// are in: per exposure (camera timestamp) that both cameras delivered, the later receive time.
Dist later_of_pair(const std::vector<std::pair<std::int64_t, std::int64_t>>& camera_receive_ns);

json to_json(const Dist& d);

// A figure in ms with `digits` decimals, "-" when it is not a number.
std::string ms(double x, int digits = 3);

struct Captured {
  std::int64_t receive_ns;
  std::string topic;
  std::vector<std::uint8_t> payload;
};

struct FrameInfo {
  std::string sensor;
  std::uint64_t sequence = 0;
  v1::FrameStatus status = v1::FRAME_STATUS_UNSPECIFIED;
  std::int64_t camera_ns = 0;
  std::int64_t receive_ns = 0;
  std::int64_t publish_ns = 0;
  double measure_us = 0;
  std::uint32_t frames_skipped = 0;
};

struct RefInfo {
  std::string sensor;
  std::uint64_t sequence = 0;
  std::int64_t camera_ns = 0;
  std::int64_t hand_receive_ns = 0;
};

// One Decision (hand_node's "decision" topic): a controller step on fresh frames.
struct DecisionInfo {
  std::int64_t time_ns = 0;
  std::vector<RefInfo> answers;
};

struct CommandInfo {
  std::uint64_t sequence = 0;
  std::int64_t send_ns = 0;
  std::string kind;  // move_to, finger_velocities, hold, open, stop
  std::vector<RefInfo> answers;
};

// A shaped camera link's queue counters (tc -s qdisc), summed over its links.
struct LinkCounters {
  std::uint64_t bytes = 0;
  std::uint64_t packets = 0;
  std::uint64_t dropped = 0;
  std::uint64_t overlimits = 0;  // packets the bucket held back (over the rate)
  int burst = 0;                 // the bucket's burst, bytes
  bool known = false;
};

struct PipelineResult {
  double fps = 0;
  double window_s = 0;
  bool task_ended_early = false;
  std::string load_at_start;
  // The rig's report (end to end over the whole run) and its counters line.
  json report;
  std::string rig_counters;
  Dist e2e;  // from the report: p50, p99, max; n = the commands' answers (unknown: 0)
  // Stages, in the measured window.
  Dist gige;       // camera timestamp -> sensor_node received the frame's last packet
  Dist gige_pair;  // the same for the later of the two frames of each exposure
  double steal_ms = std::nan("");     // the host's steal time over the window (all CPUs)
  double io_stall_ms = std::nan("");  // every task waiting for I/O at once, over the window
  // StallProbe over the window: its latest wake-up, when, and wake-ups more than 10 ms late.
  double probe_max_late_ms = std::nan("");
  std::int64_t probe_max_at_ns = 0;
  std::uint64_t probe_stalls = 0;
  bool probe_fifo = false;
  bool subscriber_idle = false;  // this benchmark's subscriber ran under SCHED_IDLE
  // Frames received before their camera timestamp: the timestamps do not say when the frame was
  // sent (the rig renders render_lead_s before the send instant; above 1/render_lead_s frames
  // per second the fake camera sends the image a period early), so latencies are not valid.
  std::uint64_t gige_negative = 0;
  Dist measure;            // received -> handed to ZeroMQ (measurement and encoding)
  Dist measure_core;       // the measurement core alone (TactileFrame.measure_time_us)
  Dist pub_recv;           // sensor_node published -> hand_node received
  Dist control;            // hand_node received the freshest answered frame -> command sent
  Dist cam_to_send_fresh;  // camera timestamp of the freshest answer -> command sent
  Dist cam_to_send_all;    // every answer (as the rig counts end to end) -> command sent
  // The same without Hold and Stop: a stale hold answers frames older than stale_after_s by
  // its very reason.
  Dist cam_to_send_all_no_hold;
  std::map<std::string, std::uint64_t> command_kinds;
  std::vector<double> cam_to_send_fresh_samples;
  // Every whole frame of the window, from hand_node's Decisions (one per step on fresh frames):
  // camera timestamp -> decided, and hand_node received -> decided; the window's whole frames
  // no Decision names (missed by this benchmark's subscriber, or never run by the controller).
  Dist cam_to_decision;
  Dist receive_to_decision;
  std::uint64_t decisions = 0;
  std::uint64_t frames_without_decision = 0;
  std::uint64_t frames = 0;
  std::uint64_t frames_complete = 0;
  std::uint64_t frames_incomplete = 0;  // status other than COMPLETE (NO_REFERENCE apart)
  std::uint64_t frames_skipped = 0;     // camera frames lost before a published frame
  std::uint64_t sequence_gaps = 0;      // TactileFrames this benchmark's subscriber missed
  std::uint64_t commands = 0;
  std::size_t frame_bytes_p50 = 0;
  std::size_t command_bytes_p50 = 0;
  std::map<std::string, double> cpu;           // percent of one core
  std::map<std::string, double> major_faults;  // in the window, per process
  // Slip onset (ground truth) -> re-compress command sent, whole run.
  std::vector<double> slip_to_recompress_ms;
  std::uint64_t recompress_events = 0;
  std::uint64_t recompress_no_command = 0;  // no command with the event's answers before it
  std::uint64_t recompress_no_onset = 0;    // no true onset of that fingertip within 3 periods
  std::uint64_t true_slip_episodes = 0;     // per fingertip, whole run
  Dist cam_to_send_all_run;                 // every answer, whole run (the rig's samples)
  json recompress_detail = json::array();
  json incomplete_run = json::array();  // every frame neither whole nor a reference frame
  double max_camera_gap_ms = 0;         // between consecutive whole frames of a sensor
  double max_publish_gap_ms = 0;
  std::uint64_t camera_gaps_over_stale = 0;  // longer than three frame periods
  std::uint64_t publish_gaps_over_stale = 0;
  json long_gaps = json::array();
  std::map<std::string, std::uint64_t> events;
  LinkCounters link;  // the cameras' link over the whole run (shaped links only)
};

// The measured window, in wall-clock (realtime) nanoseconds.
struct Window {
  std::int64_t begin_ns = 0;
  std::int64_t end_ns = 0;
  bool all_running = false;  // every program still ran at its end
  bool contains(std::int64_t t) const { return t >= begin_ns && t <= end_ns; }
};

// Decodes the capture (messages that do not decode are skipped) and fills r's figures from it:
// frame counts, sequence gaps and sizes; the stages camera -> received -> published -> hand_node
// received -> command sent and -> decided; the gaps between frames against the staleness limit of
// three periods at `fps`; the true slip episodes and slip onset -> re-compress command. The window
// `w` (realtime ns) chooses what is measured; some figures cover the whole run, as their names
// say.
void analyse_capture(const std::vector<Captured>& cap, const Window& w, double fps,
                     PipelineResult& r);

// A capture in a tactile log: one record per message (receive time, topic, payload). Throws
// std::runtime_error naming the file when it cannot be written or read, or is cut short or
// corrupt.
void write_capture(const std::filesystem::path& path, const std::vector<Captured>& cap,
                   const std::string& note);
std::vector<Captured> read_capture(const std::filesystem::path& path);

}  // namespace tactile::bench
