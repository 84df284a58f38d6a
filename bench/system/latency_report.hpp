#pragma once

// The latency benchmark's results and report (docs/benchmarks.md, "Latency and load"): the
// settings a run was made with, each rate's results (the pipeline's from latency_analysis, the
// transport alone's), latency.json's content and the tables printed on standard output. Pure
// computation and formatting: no processes, sockets or clocks.
#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "latency_analysis.hpp"
#include "tactile/calibration.hpp"

namespace tactile::bench {

struct Settings {
  std::vector<double> rates{100.0, 200.0, 500.0};
  double seconds = 20.0;            // measured wall time of each pipeline run
  double warmup_s = 2.0;            // after the task started (first ArmCommand), not measured
  double transport_seconds = 10.0;  // measured wall time of each transport-alone run
  double start_timeout_s = 60.0;    // for the task to start
  std::filesystem::path build_dir;
  std::filesystem::path scenario;
  std::filesystem::path out = "out/latency";
  bool plot = true;
  bool skip_transport = false;
  int runs = 1;  // pipeline + transport runs per rate (the p50s move between runs)
  // The cameras' regions, each run at every rate: "auto" (sensor_node's region of interest from
  // the calibration) and "full" (whole frames), as sensor_node's --roi.
  std::vector<std::string> rois{"auto", "full"};
  bool idle_subscriber = true;  // the benchmark's subscriber under SCHED_IDLE (IdleScheduling)
  // sensor_node and hand_node under SCHED_FIFO at this priority (their configurations' realtime
  // section), and the transport alone's receivers and echo likewise (FifoScheduling); 0: none.
  int realtime_priority = 0;
  // The cameras' link (scripts/camera-link): "separate" (a veth pair each, shaped to link_rate),
  // "shared" (both behind one pair) or "loopback" (127.0.0.2 and .3 beside the nodes, unshaped),
  // at MTU link_mtu (sensor_node's and the receivers' GVSP packet size).
  std::string camera_link = "separate";
  std::string link_rate = "1gbit";
  int link_mtu = 1500;
};

struct AravisResult {
  Dist latency;                    // camera timestamp -> receive_timestamp_ns, whole frames
  Dist latency_pair;               // the same for the later of the two frames of each exposure
  double steal_ms = std::nan("");  // the host's steal time over the window (all CPUs)
  std::uint64_t negative = 0;      // received before the camera timestamp (see gige_negative)
  std::uint64_t frames = 0;
  std::uint64_t complete = 0;
  std::uint64_t lost = 0;
  double receiver_cpu = std::nan("");  // this process (the two receivers), % of one core
  double rig_cpu = std::nan("");
  std::array<Region, 2> regions{};  // what each receiver set (width 0: whole frames)
  std::size_t frame_bytes = 0;      // image bytes of a whole frame received (the region's)
  LinkCounters link;                // the cameras' link over the run (shaped links only)
  // The link alone (probe_link, on a link of its own after the run): one exposure's packets.
  Dist link_alone;
  std::size_t link_alone_packets = 0;
};

struct ZmqResult {
  Dist round_trip;  // PUB -> SUB, then DEALER -> ROUTER
  Dist pub_sub;     // one way, PUB -> SUB
  Dist dealer_router;
  std::size_t frame_bytes = 0;
  std::size_t command_bytes = 0;
  std::uint64_t sent = 0;
  std::uint64_t answered = 0;
};

struct RateResult {
  int run = 1;               // of Settings::runs at this rate
  std::string roi = "auto";  // the cameras' region (Settings::rois)
  PipelineResult pipe;
  std::optional<AravisResult> aravis;
  std::optional<ZmqResult> zmq;
};

// The IP packets (bytes) a camera sends for one frame of `image_bytes` at GVSP packet size
// `packet_size` (a leader, the data packets, a trailer), as bench/system/gige_link_report.py.
std::vector<std::size_t> gvsp_frame_packets(std::size_t image_bytes, std::size_t packet_size);
constexpr std::size_t kIpUdpHeaders = 28;  // of each datagram

// The transport alone, p50: an exposure's two frames through Aravis (the later of the two), then
// one ZeroMQ round trip. NaN when either was not measured.
double transport_alone_p50(const RateResult& rr);

// The link's rate in bit/s from tc's form (1gbit, 500mbit, 100kbit); NaN for another form.
double rate_bps(const std::string& rate);

// One rate's run as latency.json holds it.
json result_json(const RateResult& rr);

// Every table of the report, on standard output.
void print_tables(const std::vector<RateResult>& rs, const Settings& s);

}  // namespace tactile::bench
