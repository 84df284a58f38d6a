// Latency and load of the whole system (docs/benchmarks.md, "Latency and load").
//
// For each frame rate, with two cameras, in one private loopback network namespace:
//   1. the pipeline: the real rig (real time), sensor_node and hand_node as processes, with the
//      configurations `rig --write-configs` writes for a copy of the scenario at that rate, for a
//      fixed wall time after the task started. End to end (camera timestamp -> ArmCommand
//      received by the arm controller) is the rig's own report; the stages come from the
//      timestamps on the wire (TactileFrames, and the copies of ArmCommands hand_node publishes
//      beside its events); CPU per process from /proc/<pid>/stat; slip onset -> re-compress
//      command from the rig's ground truth and hand_node's RECOMPRESS events.
//   2. the transport alone, in the same run: the rig's fake GigE Vision cameras to a plain
//      Aravis receiver (tactile::camera::AravisCamera, what sensor_node uses, nothing else), and
//      a ZeroMQ round trip (PUB/SUB out, DEALER/ROUTER back, through an echo process) with
//      messages the size of the run's TactileFrames and ArmCommands, at the same rate.
// Each rate runs once per camera region of --roi (default both): `auto`, the region of interest
// sensor_node sets from the calibrations (its default), and `full`, whole frames; the transport
// alone receives the same region as the pipeline beside it, so the two are compared like for like.
// Prints a table, writes OUT/latency.json and OUT/latency.png; progress on standard error.
#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <sched.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "camera_link.hpp"
#include "host_load.hpp"
#include "latency_analysis.hpp"
#include "latency_report.hpp"
#include "supervision.hpp"
#include "tactile/calibration.hpp"
#include "tactile/camera/aravis_camera.hpp"
#include "tactile/camera/private_network.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/plot/figure.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/host_load.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/percentile.hpp"
#include "tactile/util/process.hpp"
#include "tactile/util/realtime.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile::bench {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using std::chrono::milliseconds;

// ------------------------------------------------------------------------------------------
// The pipeline: rig, sensor_node, hand_node

fs::path program(const Settings& s, const char* rel) {
  const fs::path p = s.build_dir / rel;
  if (!fs::exists(p))
    throw std::runtime_error(
        fmt::format("{} is missing: build it first (cmake --build {} --target "
                    "rig sensor_node hand_node)",
                    p.string(), s.build_dir.string()));
  return p;
}

// A copy of the scenario at `fps`, long enough that the rig never stops on its own first.
fs::path write_scenario(const Settings& s, double fps, double max_time_s, const fs::path& dir) {
  YAML::Node node;
  try {
    node = YAML::LoadFile(s.scenario.string());
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("{}: {}", s.scenario.string(), e.what()));
  }
  if (!node["camera"] || !node["camera"].IsMap())
    throw std::runtime_error(fmt::format("{}: no camera section", s.scenario.string()));
  node["camera"]["fps"] = fps;
  node["sim"]["max_time_s"] = max_time_s;
  const fs::path path = dir / fmt::format("scenario-{}fps.yaml", fps);
  YAML::Emitter em;
  em << node;
  util::write_file_atomic(path, std::string(em.c_str()) + "\n");
  return path;
}

void run_checked(const std::string& name, std::vector<std::string> argv, const fs::path& log) {
  Child c(name, std::move(argv), log);
  // Waited for, not stopped at once: a SIGINT before the program set its handler killed it.
  if (c.wait(milliseconds(30000)) != 0)
    throw std::runtime_error(
        fmt::format("{} failed (status {}):{}", name, c.exit_code(), tail_of(log)));
}

void capture_until(wire::Subscriber& sub, std::vector<Captured>& into, std::int64_t until_mono_ns,
                   const std::vector<Child*>& children, const std::function<bool()>& done) {
  wire::TopicMessage m;
  std::array<zmq::socket_ref, 1> socks{sub.socket()};
  while (util::monotonic_ns() < until_mono_ns && !util::stop_requested()) {
    wire::poll_readable(socks, milliseconds(20));
    while (sub.receive(m, milliseconds(0)))
      into.push_back({util::realtime_ns(), m.topic, m.payload});
    for (Child* c : children) {
      if (!c->running()) return;
    }
    if (done && done()) break;
  }
}

struct Programs {
  fs::path rig;
  fs::path sensor;
  fs::path hand;
};

Programs find_programs(const Settings& s) {
  return {program(s, "rig/rig"), program(s, "sensor_node/sensor_node"),
          program(s, "hand_node/hand_node")};
}

// The scenario at `fps` and the programs' configurations from rig --write-configs, with the
// real-time priority added when asked for. Returns the scenario.
fs::path write_configs(const Settings& s, double fps, const fs::path& dir, const fs::path& rig,
                       const CameraLink& link) {
  const double budget = s.start_timeout_s + s.warmup_s + s.seconds + 60.0;
  const fs::path scenario = write_scenario(s, fps, budget, dir);
  std::vector<std::string> argv{rig.string(), "--scenario", scenario.string(), "--write-configs",
                                (dir / "config").string()};
  const std::vector<std::string> on_link = link.rig_options();
  argv.insert(argv.end(), on_link.begin(), on_link.end());
  // sensor_node's GVSP packets fit the link's MTU.
  if (!on_link.empty())
    argv.insert(argv.end(), {"--camera-packet-size", std::to_string(s.link_mtu)});
  run_checked("rig --write-configs", argv, dir / "logs" / "rig.log");
  if (s.realtime_priority > 0) {
    for (const char* f : {"sensor_node.yaml", "hand_node.yaml"}) {
      std::ofstream out(dir / "config" / f, std::ios::app);
      out << fmt::format("realtime: {{priority: {}}}\n", s.realtime_priority);
      if (!out)
        throw std::runtime_error(fmt::format("cannot append to {}", (dir / "config" / f).string()));
    }
  }
  return scenario;
}

// Stops every program and throws `what`, with the log tails of those that had already ended.
[[noreturn]] void fail_run(const std::string& what, const std::vector<Child*>& children,
                           const fs::path& dir) {
  std::string msg = what;
  for (Child* c : children) {
    if (!c->running())
      msg += fmt::format("\n  {} exited with status {}; its log ends:{}", c->name(), c->exit_code(),
                         tail_of(dir / "logs" / (c->name() + ".log")));
  }
  for (Child* c : children)
    c->stop(milliseconds(3000));
  throw std::runtime_error(msg);
}

// Captures until hand_node sends its first command (it has both fingertips and the arm: the task
// starts). False if it did not within the start timeout.
bool wait_for_task(const Settings& s, wire::Subscriber& sub, std::vector<Captured>& cap,
                   const std::vector<Child*>& children) {
  std::size_t seen = 0;
  bool started = false;
  capture_until(sub, cap, util::monotonic_ns() + static_cast<std::int64_t>(s.start_timeout_s * 1e9),
                children, [&] {
                  for (; seen < cap.size(); ++seen) {
                    if (cap[seen].topic == wire::kCommandTopic) started = true;
                  }
                  return started;
                });
  return started;
}

// Captures for s.seconds while sampling the programs' CPU, the host's steal and I/O stalls and a
// stall probe; fills those figures into r.
Window measure_window(const Settings& s, double fps, wire::Subscriber& sub,
                      std::vector<Captured>& cap, const std::vector<Child*>& children,
                      const std::map<std::string, pid_t>& pids, PipelineResult& r) {
  Window w;
  CpuWindow cpu;
  cpu.begin(pids);
  const double steal0 = util::steal_ms();
  const double io0 = io_full_stall_ms();
  w.begin_ns = util::realtime_ns();
  const std::int64_t m0 = util::monotonic_ns();
  progress(fmt::format("{:.0f} fps: task started; measuring {} s", fps, s.seconds));
  std::int64_t sampled = m0;
  StallProbe probe;
  capture_until(sub, cap, m0 + static_cast<std::int64_t>(s.seconds * 1e9), children, [&] {
    if (util::monotonic_ns() - sampled > 250'000'000) {
      cpu.sample(pids);
      sampled = util::monotonic_ns();
    }
    return false;
  });
  probe.stop();
  r.probe_max_late_ms = probe.max_late_ms();
  r.probe_max_at_ns = probe.max_at_ns();
  r.probe_stalls = probe.stalls_over_10ms();
  r.probe_fifo = probe.fifo();
  w.all_running =
      std::all_of(children.begin(), children.end(), [](Child* c) { return c->running(); });
  r.cpu = cpu.end(pids);
  r.major_faults = cpu.major_faults();
  r.steal_ms = util::steal_ms() - steal0;
  r.io_stall_ms = io_full_stall_ms() - io0;
  w.end_ns = util::realtime_ns();
  r.window_s = static_cast<double>(w.end_ns - w.begin_ns) * 1e-9;
  return w;
}

// The rig's report (end to end over the whole run) and the counters line of its log.
void read_rig_report(const fs::path& report, const fs::path& log_path, PipelineResult& r) {
  r.report = json::parse(std::ifstream(report));
  std::ifstream log(log_path);
  for (std::string l; std::getline(log, l);) {
    const auto at = l.find("frames rendered");
    if (at != std::string::npos) r.rig_counters = l.substr(at);
  }
  if (r.report.contains("latency_ms") && r.report["latency_ms"].is_object()) {
    const json& l = r.report["latency_ms"];
    r.e2e.p50 = l.value("p50", std::nan(""));
    r.e2e.p99 = l.value("p99", std::nan(""));
    r.e2e.max = l.value("max", std::nan(""));
  }
}

// rig, sensor_node and hand_node as processes, started in this order, each logging to
// dir/logs/<name>.log; the rig writes its report to dir/report.json when stopped.
class PipelineProcesses {
 public:
  PipelineProcesses(const Settings& s, const Programs& prog, const fs::path& scenario,
                    const std::string& roi, const CameraLink& link, const fs::path& dir)
      : dir_(dir),
        report_(dir / "report.json"),
        rig_(
            "rig",
            [&] {
              std::vector<std::string> argv{prog.rig.string(),
                                            "--scenario",
                                            scenario.string(),
                                            "--report",
                                            report_.string(),
                                            "--wait-for-hand",
                                            fmt::format("{}", s.start_timeout_s),
                                            "--log-level",
                                            "debug"};
              const std::vector<std::string> on_link = link.rig_options();
              argv.insert(argv.end(), on_link.begin(), on_link.end());
              return argv;
            }(),
            dir / "logs" / "rig.log"),
        sensor_("sensor_node",
                {prog.sensor.string(), "--config", (dir / "config" / "sensor_node.yaml").string(),
                 "--roi", roi},
                dir / "logs" / "sensor_node.log"),
        hand_("hand_node",
              {prog.hand.string(), "--config", (dir / "config" / "hand_node.yaml").string()},
              dir / "logs" / "hand_node.log") {}

  const std::vector<Child*>& children() const { return children_; }
  std::map<std::string, pid_t> pids() const {
    return {{"rig", rig_.pid()},
            {"sensor_node", sensor_.pid()},
            {"hand_node", hand_.pid()},
            {"benchmark", ::getpid()}};
  }
  bool rig_running() { return rig_.running(); }
  [[noreturn]] void fail(const std::string& what) const { fail_run(what, children_, dir_); }

  // The nodes first (a sensor_node whose cameras vanished first spends seconds giving up on
  // them), then the rig, which writes its report on SIGINT; the report read into r.
  void stop(double fps, PipelineResult& r) {
    hand_.stop(milliseconds(5000));
    sensor_.stop(milliseconds(10000));
    const int rig_status = rig_.stop(milliseconds(10000));
    if (rig_status != 0 || !fs::exists(report_))
      fail(fmt::format("{:.0f} fps: the rig wrote no report (status {})", fps, rig_status));
    read_rig_report(report_, dir_ / "logs" / "rig.log", r);
  }

 private:
  fs::path dir_;
  fs::path report_;
  Child rig_;
  Child sensor_;
  Child hand_;
  std::vector<Child*> children_{&rig_, &sensor_, &hand_};
};

PipelineResult run_pipeline(const Settings& s, double fps, const std::string& roi,
                            const fs::path& dir) {
  PipelineResult r;
  r.fps = fps;
  fs::create_directories(dir / "config");
  fs::create_directories(dir / "logs");
  const Programs prog = find_programs(s);
  CameraLink link(s, dir / "logs" / "camera-link.log");
  const fs::path scenario = write_configs(s, fps, dir, prog.rig, link);

  // Declared before the context: the context's I/O thread starts under it, and ends before it.
  const IdleScheduling idle(s.idle_subscriber);
  r.subscriber_idle = idle.active();
  zmq::context_t ctx;
  // Everything the programs publish that the stages need; the rig's truth for slip onsets.
  wire::Subscriber sub(ctx,
                       {"tcp://127.0.0.1:5555", "tcp://127.0.0.1:5557", "tcp://127.0.0.1:5558"},
                       {wire::kFrameTopicPrefix, wire::kTruthTopic, wire::kEventTopic,
                        wire::kCommandTopic, wire::kDecisionTopic});
  std::vector<Captured> cap;
  cap.reserve(static_cast<std::size_t>(fps * 4 * (s.seconds + s.warmup_s + 30)));

  r.load_at_start = util::load_average();
  PipelineProcesses procs(s, prog, scenario, roi, link, dir);
  progress(fmt::format(
      "{:.0f} fps, roi {}: rig, sensor_node and hand_node started; waiting for the task", fps,
      roi));
  if (!wait_for_task(s, sub, cap, procs.children()))
    procs.fail(
        fmt::format("{:.0f} fps: the task did not start within {} s", fps, s.start_timeout_s));
  capture_until(sub, cap, util::monotonic_ns() + static_cast<std::int64_t>(s.warmup_s * 1e9),
                procs.children(), {});

  const Window w = measure_window(s, fps, sub, cap, procs.children(), procs.pids(), r);
  if (util::stop_requested()) procs.fail("interrupted");
  if (!w.all_running) {
    // The task may end (DONE or a drop, then the rig stops) before the window does: that is a
    // result; CPU is then over the time up to each process's last sample.
    r.task_ended_early = true;
    if (procs.rig_running())
      procs.fail(fmt::format("{:.0f} fps: a program stopped during the run", fps));
    progress(
        fmt::format("{:.0f} fps: the task ended after {:.1f} s of the window", fps, r.window_s));
  }
  procs.stop(fps, r);
  r.link = link.stop();

  // Decode after the run: nothing but copying competes with the programs while they run. The
  // capture is kept beside the logs, so that the figures can be computed again from it.
  write_capture(
      dir / "capture.tlog", cap,
      fmt::format("{:.0f} fps, roi {}, window {} to {} ns", fps, roi, w.begin_ns, w.end_ns));
  analyse_capture(cap, w, fps, r);
  return r;
}

// ------------------------------------------------------------------------------------------
// The transport alone

// The rig alone serves its two fake cameras (the same images, rate and timestamps as in the
// pipeline); a plain Aravis receiver per camera in this process takes the frames and does
// nothing with them. With roi "auto" each receiver sets the region of interest sensor_node set
// in the pipeline run (from the calibrations that run's configuration holds, dir/config).
AravisResult run_aravis(const Settings& s, double fps, const std::string& roi,
                        const fs::path& dir) {
  AravisResult r;
  const fs::path rig = program(s, "rig/rig");
  const double budget = s.transport_seconds + 60.0;
  const fs::path scenario = write_scenario(s, fps, budget, dir);
  const YAML::Node sc = YAML::LoadFile(scenario.string());
  const int width = sc["camera"]["width"].as<int>(640);
  const int height = sc["camera"]["height"].as<int>(480);
  const int depth = sc["camera"]["bit_depth"].as<int>(8);
  CameraLink link(s, dir / "logs" / "transport-camera-link.log");
  std::vector<std::string> rig_argv{rig.string(),
                                    "--scenario",
                                    scenario.string(),
                                    "--wait-for-hand",
                                    fmt::format("{}", budget),
                                    "--report",
                                    (dir / "transport-rig.json").string()};
  const std::vector<std::string> on_link = link.rig_options();
  rig_argv.insert(rig_argv.end(), on_link.begin(), on_link.end());
  Child rig_p("rig", rig_argv, dir / "logs" / "transport-rig.log");
  for (const std::string& address : link.cameras()) {
    const std::int64_t deadline = util::monotonic_ns() + 30'000'000'000;
    while (!camera::gvcp_device_answers(address, milliseconds(200))) {
      if (!rig_p.running() || util::monotonic_ns() > deadline)
        throw std::runtime_error(fmt::format("transport: the rig's camera {} never answered:{}",
                                             address, tail_of(dir / "logs" / "transport-rig.log")));
    }
  }
  // Before the receivers: their stream threads inherit it.
  const FifoScheduling fifo(s.realtime_priority);
  std::vector<std::unique_ptr<camera::AravisCamera>> receivers;
  // rig --write-configs names the calibrations after the fingertips, in the cameras' order.
  constexpr const char* kCalibrations[2] = {"left.yaml", "right.yaml"};
  for (std::size_t c = 0; c < 2; ++c) {
    camera::AravisCameraOptions o;
    o.camera = link.cameras()[c];
    if (!on_link.empty()) o.packet_size_bytes = s.link_mtu;
    o.width = width;
    o.height = height;
    o.pixel_format = depth == 16 ? PixelFormat::kMono16 : PixelFormat::kMono8;
    o.frame_rate_hz = fps;
    if (roi == "auto")
      o.region = region_of_interest(config::load_calibration(dir / "config" / kCalibrations[c]));
    r.regions[c] = o.region;
    receivers.push_back(std::make_unique<camera::AravisCamera>(o));
    receivers.back()->start();
  }
  const std::int64_t warmup_ns = 1'000'000'000;
  const auto measure_ns = static_cast<std::int64_t>(s.transport_seconds * 1e9);
  const std::int64_t begin = util::monotonic_ns();
  std::array<std::vector<double>, 2> lat;
  std::array<std::vector<std::pair<std::int64_t, std::int64_t>>, 2> lat_ns;
  std::array<AravisResult, 2> counts;
  {
    std::vector<std::jthread> threads;
    for (std::size_t c = 0; c < 2; ++c) {
      threads.emplace_back([&, c] {
        lat[c].reserve(static_cast<std::size_t>(fps * s.transport_seconds * 1.2) + 16);
        lat_ns[c].reserve(lat[c].capacity());
        while (util::monotonic_ns() < begin + warmup_ns + measure_ns) {
          const camera::Frame f = receivers[c]->wait_frame(milliseconds(200));
          if (!f.received || util::monotonic_ns() < begin + warmup_ns) continue;
          ++counts[c].frames;
          counts[c].lost += f.frames_lost;
          if (f.status != camera::FrameStatus::kComplete) continue;
          ++counts[c].complete;
          counts[c].frame_bytes = static_cast<std::size_t>(f.image.width) *
                                  static_cast<std::size_t>(f.image.height) *
                                  (f.image.format == PixelFormat::kMono16 ? 2U : 1U);
          lat[c].push_back(static_cast<double>(f.receive_timestamp_ns - f.camera_timestamp_ns) *
                           1e-6);
          lat_ns[c].emplace_back(f.camera_timestamp_ns, f.receive_timestamp_ns);
          receivers[c]->release_frame();
        }
      });
    }
    while (util::monotonic_ns() < begin + warmup_ns)
      std::this_thread::sleep_for(milliseconds(5));
    const std::map<std::string, pid_t> pids{{"receiver", ::getpid()}, {"rig", rig_p.pid()}};
    CpuWindow cpu;
    cpu.begin(pids);
    const double steal0 = util::steal_ms();
    while (util::monotonic_ns() < begin + warmup_ns + measure_ns)
      std::this_thread::sleep_for(milliseconds(5));
    const auto pct = cpu.end(pids);
    r.steal_ms = util::steal_ms() - steal0;
    r.receiver_cpu = pct.at("receiver");
    r.rig_cpu = pct.at("rig");
  }
  for (auto& rc : receivers)
    rc->stop();
  receivers.clear();
  rig_p.stop(milliseconds(10000));
  r.link = link.stop();
  r.frame_bytes = std::max(counts[0].frame_bytes, counts[1].frame_bytes);
  if (s.camera_link != "loopback" && r.frame_bytes > 0) {
    // The packets of one exposure on a link, as wire_time_ms counts them (its frame's, or both
    // frames' on a shared link, at the link's MTU), as UDP payloads, sent through a fresh link
    // so its counters stay the run's.
    std::vector<std::size_t> sizes;
    for (int frame = 0; frame < (s.camera_link == "shared" ? 2 : 1); ++frame)
      for (const std::size_t ip :
           gvsp_frame_packets(r.frame_bytes, static_cast<std::size_t>(s.link_mtu)))
        sizes.push_back(ip - kIpUdpHeaders);
    r.link_alone_packets = sizes.size();
    CameraLink alone(s, dir / "logs" / "link-alone-camera-link.log");
    r.link_alone = probe_link(alone, sizes, 200);
    alone.stop();
  }
  std::vector<double> both = lat[0];
  both.insert(both.end(), lat[1].begin(), lat[1].end());
  r.latency = dist(both);
  std::vector<std::pair<std::int64_t, std::int64_t>> both_ns = lat_ns[0];
  both_ns.insert(both_ns.end(), lat_ns[1].begin(), lat_ns[1].end());
  r.latency_pair = later_of_pair(both_ns);
  r.negative = static_cast<std::uint64_t>(
      std::count_if(both.begin(), both.end(), [](double x) { return x < 0; }));
  for (const AravisResult& c : counts) {
    r.frames += c.frames;
    r.complete += c.complete;
    r.lost += c.lost;
  }
  return r;
}

// Echo process: every message on SUB goes back over DEALER at `reply_bytes`, carrying the
// sender's stamp and the time it arrived here.
int zmq_echo(const std::string& pub_endpoint, const std::string& router_endpoint,
             std::size_t reply_bytes, int realtime_priority) {
  util::apply_realtime_scheduling({realtime_priority, false}, "zmq-echo");
  util::install_stop_handlers();
  zmq::context_t ctx;
  wire::Subscriber sub(ctx, {pub_endpoint}, {wire::kFrameTopicPrefix});
  wire::Dealer dealer(ctx, router_endpoint);
  std::vector<std::uint8_t> reply(std::max<std::size_t>(reply_bytes, 24));
  // Announce ourselves so the ROUTER knows the peer.
  std::memset(reply.data(), 0, reply.size());
  dealer.send(reply);
  wire::TopicMessage m;
  std::array<zmq::socket_ref, 1> socks{sub.socket()};
  while (!util::stop_requested()) {
    wire::poll_readable(socks, milliseconds(100));
    while (sub.receive(m, milliseconds(0))) {
      const std::int64_t now = util::realtime_ns();
      if (m.payload.size() < 16) continue;
      std::memcpy(reply.data(), m.payload.data(), 16);
      std::memcpy(reply.data() + 16, &now, 8);
      dealer.send(reply);
    }
  }
  return 0;
}

ZmqResult run_zmq(const Settings& s, double fps, std::size_t frame_bytes, std::size_t command_bytes,
                  const fs::path& self, const fs::path& dir) {
  ZmqResult r;
  r.frame_bytes = std::max<std::size_t>(frame_bytes, 24);
  r.command_bytes = std::max<std::size_t>(command_bytes, 24);
  // Before the context, whose I/O thread inherits it. This side stands for sensor_node's PUB and
  // for the rig's ROUTER, which in the pipeline runs at the normal policy: with
  // --realtime-priority the baseline is, if anything, favoured (the "added" figure errs high).
  const FifoScheduling fifo(s.realtime_priority);
  zmq::context_t ctx;
  wire::Publisher pub(ctx, "tcp://127.0.0.1:*");
  wire::Router router(ctx, "tcp://127.0.0.1:*");
  const auto local = [](std::string e) {
    const auto at = e.find("0.0.0.0");
    if (at != std::string::npos) e.replace(at, 7, "127.0.0.1");
    return e;
  };
  Child echo("zmq-echo",
             {self.string(), "--zmq-echo", local(pub.endpoint()), local(router.endpoint()),
              std::to_string(r.command_bytes), std::to_string(s.realtime_priority)},
             dir / "logs" / "zmq-echo.log");
  std::string peer;
  std::vector<std::uint8_t> in;
  // Wait for the echo's hello, then for the subscription to take (slow joiner).
  const std::int64_t deadline = util::monotonic_ns() + 10'000'000'000;
  while (!router.receive(peer, in, milliseconds(50))) {
    if (!echo.running() || util::monotonic_ns() > deadline)
      throw std::runtime_error("transport: the ZeroMQ echo process did not connect:" +
                               tail_of(dir / "logs" / "zmq-echo.log"));
  }
  std::vector<std::uint8_t> msg(r.frame_bytes, 0x5a);
  const std::array<std::string, 2> topics{wire::frame_topic("left"), wire::frame_topic("right")};
  const auto period_ns = static_cast<std::int64_t>(1e9 / fps);
  const std::int64_t warmup_ns = 1'000'000'000;
  const auto measure_ns = static_cast<std::int64_t>(s.transport_seconds * 1e9);
  const std::int64_t begin = util::monotonic_ns();
  std::int64_t next = begin;
  std::uint64_t seq = 0;
  std::vector<double> rtt;
  std::vector<double> out_leg;
  std::vector<double> back_leg;
  std::array<zmq::socket_ref, 1> socks{router.socket()};
  const std::uint64_t first_measured = static_cast<std::uint64_t>(2 * warmup_ns / period_ns);
  while (util::monotonic_ns() < begin + warmup_ns + measure_ns + 100'000'000) {
    const std::int64_t now = util::monotonic_ns();
    if (now >= next && now < begin + warmup_ns + measure_ns) {
      // Two sensors: two frames each period, as sensor_node publishes them.
      for (const std::string& topic : topics) {
        const std::int64_t t = util::realtime_ns();
        ++seq;
        std::memcpy(msg.data(), &t, 8);
        std::memcpy(msg.data() + 8, &seq, 8);
        pub.send(topic, msg);
        if (seq > first_measured) ++r.sent;
      }
      next += period_ns;
    }
    const std::int64_t wait = std::max<std::int64_t>(0, next - util::monotonic_ns());
    wire::poll_readable(socks, milliseconds(std::min<std::int64_t>(wait / 1'000'000, 5)));
    while (router.receive(peer, in, milliseconds(0))) {
      const std::int64_t t_back = util::realtime_ns();
      if (in.size() < 24) continue;
      std::int64_t t_sent = 0;
      std::uint64_t n = 0;
      std::int64_t t_echo = 0;
      std::memcpy(&t_sent, in.data(), 8);
      std::memcpy(&n, in.data() + 8, 8);
      std::memcpy(&t_echo, in.data() + 16, 8);
      if (n <= first_measured || t_sent == 0) continue;
      ++r.answered;
      rtt.push_back(static_cast<double>(t_back - t_sent) * 1e-6);
      out_leg.push_back(static_cast<double>(t_echo - t_sent) * 1e-6);
      back_leg.push_back(static_cast<double>(t_back - t_echo) * 1e-6);
    }
  }
  echo.stop(milliseconds(3000));
  r.round_trip = dist(rtt);
  r.pub_sub = dist(out_leg);
  r.dealer_router = dist(back_leg);
  return r;
}

void write_plot(const std::vector<RateResult>& rs, const fs::path& path) {
  plot::Figure fig(900, 220 * static_cast<int>(std::max<std::size_t>(rs.size(), 1)) + 80);
  fig.title("camera timestamp -> ArmCommand sent (freshest answered frame), two cameras");
  fig.share_x();
  // The axis spans the bulk (1.5 times the largest p90), not a pause of the machine tens of
  // milliseconds long; what lies beyond is counted in the legend.
  double hi = 0;
  for (const RateResult& rr : rs) {
    const auto& v = rr.pipe.cam_to_send_fresh_samples;
    if (!v.empty()) hi = std::max(hi, 1.5 * percentile(v, 0.90));
  }
  if (hi <= 0) return;
  for (std::size_t i = 0; i < rs.size(); ++i) {
    std::vector<double> in_range;
    for (const double x : rs[i].pipe.cam_to_send_fresh_samples) {
      if (x <= hi) in_range.push_back(x);
    }
    const std::size_t beyond = rs[i].pipe.cam_to_send_fresh_samples.size() - in_range.size();
    auto& panel = fig.add_panel();
    panel.x_label("latency [ms]").y_label("commands");
    plot::Style st;
    st.color = plot::palette(i);
    const std::string rate =
        fmt::format("{:.0f} fps, {}", rs[i].pipe.fps,
                    rs[i].roi == "auto" ? "region of interest" : "whole frames");
    const std::string label = beyond == 0
                                  ? rate
                                  : fmt::format("{} ({} beyond {:.2f} ms, max {:.1f} ms)", rate,
                                                beyond, hi, rs[i].pipe.cam_to_send_fresh.max);
    panel.histogram(in_range, 60, label, st, 0.0, hi);
  }
  fig.save_png(path);
}

int run(const Settings& s, const fs::path& self) {
  camera::enter_private_network({kCameraAddresses[0], kCameraAddresses[1]});
  util::install_stop_handlers();
  fs::create_directories(s.out / "logs");
  progress(fmt::format("build {}, scenario {}, output {}; {} cores, load average {}",
                       s.build_dir.string(), s.scenario.string(), s.out.string(),
                       std::thread::hardware_concurrency(), util::load_average()));
  std::vector<RateResult> results;
  json all;
  all["machine"] = {{"cores", std::thread::hardware_concurrency()},
                    {"load_average_at_start", util::load_average()}};
  all["settings"] = {{"seconds", s.seconds},
                     {"warmup_s", s.warmup_s},
                     {"transport_seconds", s.transport_seconds},
                     {"runs", s.runs},
                     {"rois", s.rois},
                     {"realtime_priority", s.realtime_priority},
                     {"camera_link", s.camera_link},
                     {"link_rate", s.link_rate},
                     {"link_mtu", s.link_mtu},
                     {"scenario", s.scenario.string()}};
  for (const double fps : s.rates) {
    for (int run = 1; run <= s.runs; ++run) {
      const fs::path run_dir = s.runs > 1
                                   ? s.out / fmt::format("{}fps", fps) / fmt::format("run{}", run)
                                   : s.out / fmt::format("{}fps", fps);
      if (s.runs > 1) progress(fmt::format("{:.0f} fps: run {} of {}", fps, run, s.runs));
      // The regions one after the other within a run, so both meet the same machine.
      for (const std::string& roi : s.rois) {
        const fs::path dir = s.rois.size() > 1 ? run_dir / ("roi-" + roi) : run_dir;
        const std::string at = fmt::format("{:.0f} fps, roi {}", fps, roi);
        fs::create_directories(dir / "logs");
        RateResult rr;
        rr.run = run;
        rr.roi = roi;
        rr.pipe = run_pipeline(s, fps, roi, dir);
        progress(
            fmt::format("{}: end to end p50 {} ms, p99 {} ms, max {} ms; {} frames, {} incomplete",
                        at, ms(rr.pipe.e2e.p50), ms(rr.pipe.e2e.p99), ms(rr.pipe.e2e.max),
                        rr.pipe.frames, rr.pipe.frames_incomplete));
        if (!s.skip_transport) {
          progress(
              fmt::format("{}: transport alone, Aravis receive ({} s)", at, s.transport_seconds));
          rr.aravis = run_aravis(s, fps, roi, dir);
          progress(fmt::format("{}: transport alone, ZeroMQ round trip ({} s)", at,
                               s.transport_seconds));
          rr.zmq = run_zmq(s, fps, rr.pipe.frame_bytes_p50, rr.pipe.command_bytes_p50, self, dir);
        }
        all["rates"].push_back(result_json(rr));
        results.push_back(std::move(rr));
        util::write_file_atomic(s.out / "latency.json", all.dump(2) + "\n");
      }
    }
  }
  print_tables(results, s);
  progress(fmt::format("wrote {}", (s.out / "latency.json").string()));
  if (s.plot) {
    // A panel per rate and region: its first run.
    std::vector<RateResult> first;
    std::copy_if(results.begin(), results.end(), std::back_inserter(first),
                 [](const RateResult& rr) { return rr.run == 1; });
    write_plot(first, s.out / "latency.png");
    progress(fmt::format("wrote {}", (s.out / "latency.png").string()));
  }
  return 0;
}

}  // namespace
}  // namespace tactile::bench

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_system_latency_bench");
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  // Hidden role: the echo end of the ZeroMQ round trip (started by the benchmark itself).
  if (argc == 6 && std::string(argv[1]) == "--zmq-echo") {
    try {
      return tactile::bench::zmq_echo(argv[2], argv[3], std::stoul(argv[4]), std::stoi(argv[5]));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "zmq-echo: %s\n", e.what());
      return 1;
    }
  }
  tactile::bench::Settings s;
  // build/bench/system/<this program>: the build directory is three levels up.
  if (!ec) s.build_dir = self.parent_path().parent_path().parent_path();
  s.scenario = fs::path(TACTILE_SOURCE_DIR) / "rig" / "scenarios" / "default.yaml";
  CLI::App app(
      "tactile_system_latency_bench: latency and load of the whole system (docs/benchmarks.md, "
      "\"Latency and load\").\nFor each rate, with two cameras, in a private network namespace "
      "(the cameras behind shaped links by default, --camera-link): the real rig (real time), "
      "sensor_node and hand_node as processes, then the "
      "transport alone (the rig's fake GigE Vision cameras to a plain Aravis receiver; a ZeroMQ "
      "PUB/SUB + DEALER/ROUTER round trip). Prints tables, writes OUT/latency.json and "
      "OUT/latency.png, the programs' logs and configurations under OUT/<fps>fps/roi-<roi>/.");
  app.add_option("--fps", s.rates, "frame rates, both cameras")
      ->delimiter(',')
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--seconds", s.seconds, "measured wall time per rate, after the task started")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  app.add_option("--warmup", s.warmup_s, "unmeasured time after the task started (s)")
      ->check(CLI::Range(0.0, 600.0))
      ->capture_default_str();
  app.add_option("--transport-seconds", s.transport_seconds,
                 "measured wall time of each transport-alone run")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  app.add_option("--start-timeout", s.start_timeout_s, "give up when the task has not started (s)")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  app.add_option("--build", s.build_dir,
                 "build directory holding the built rig, sensor_node and hand_node")
      ->capture_default_str();
  app.add_option("--scenario", s.scenario, "scenario file; its camera fps is replaced by each rate")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--out", s.out, "output directory")->capture_default_str();
  app.add_option("--roi", s.rois,
                 "the cameras' regions, each run at every rate: auto (sensor_node's region of "
                 "interest from the calibrations, its default) and full (whole frames); the "
                 "transport alone receives the same region")
      ->delimiter(',')
      ->check(CLI::IsMember({"auto", "full"}))
      ->capture_default_str();
  app.add_option("--camera-link", s.camera_link,
                 "the cameras' link (scripts/camera-link): loopback (beside the nodes, unshaped), "
                 "shared (both cameras behind one veth pair shaped to --link-rate) or separate "
                 "(one each); the transport alone runs on the same link")
      ->check(CLI::IsMember({"loopback", "shared", "separate"}))
      ->capture_default_str();
  app.add_option("--link-rate", s.link_rate, "the shaped link's rate, in tc's form")
      ->check([](const std::string& v) {
        return std::isfinite(tactile::bench::rate_bps(v))
                   ? std::string()
                   : "give tc's form, e.g. 1gbit or 500mbit, not '" + v + "'";
      })
      ->capture_default_str();
  app.add_option("--link-mtu", s.link_mtu,
                 "the shaped link's MTU, and the GVSP packet size of sensor_node and the receivers")
      ->check(CLI::IsMember({1500, 9000}))
      ->capture_default_str();
  app.add_flag("!--no-plot", s.plot, "do not write latency.png");
  app.add_flag("--skip-transport", s.skip_transport, "only the pipeline, not the transport alone");
  app.add_option("--runs", s.runs,
                 "runs per rate, each the pipeline then the transport alone; the tables give "
                 "every run and the median of their p50s")
      ->check(CLI::Range(1, 100));
  app.add_flag("!--normal-subscriber", s.idle_subscriber,
               "run the benchmark's own subscriber at the normal policy, competing with the "
               "programs for the CPUs (the default runs it under SCHED_IDLE)");
  app.add_option("--realtime-priority", s.realtime_priority,
                 "run sensor_node and hand_node under SCHED_FIFO at this priority (their "
                 "configuration's realtime section), and the transport alone's receivers and "
                 "ZeroMQ ends likewise; needs root or CAP_SYS_NICE (default 0: the normal policy)")
      ->check(CLI::Range(0, 98));
  return tactile::cli::run(app, argc, argv, [&] {
    if (std::set<std::string>(s.rois.begin(), s.rois.end()).size() != s.rois.size())
      throw tactile::cli::UsageError("--roi names a region twice");
    // Refused now rather than after the first run: try it once on this thread and drop it.
    { const tactile::bench::FifoScheduling probe(s.realtime_priority); }
    return tactile::bench::run(s, self);
  });
}
