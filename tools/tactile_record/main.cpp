// tactile_record: subscribes to sensor_node, hand_node and rig publishers and writes every message,
// with its topic, source and receive time, to one log file (docs/recording.md).
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/cli/run.hpp"
#include "tactile/recording/log_writer.hpp"
#include "tactile/recording/sources.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"

namespace {

using tactile::recording::LogWriter;
using tactile::recording::Sources;
using tactile::recording::WriteStatus;

constexpr const char* kVersion = "tactile_record 0.1.0";

struct Options {
  std::vector<std::string> endpoints;
  std::vector<std::string> curve;
  std::string client_key;
  std::string output;
  // Everything but raw frames: sensors, hand_node (events, the ArmStates it received, the
  // ArmCommands it sent) and the rig's truth.
  std::vector<std::string> topics{
      tactile::wire::kFrameTopicPrefix, tactile::wire::kStatsTopicPrefix,
      tactile::wire::kEventTopic,       tactile::wire::kArmTopic,
      tactile::wire::kCommandTopic,     tactile::wire::kDecisionTopic,
      tactile::wire::kTruthTopic};
  bool raw_frames = false;
  double duration_s = 0;
  std::uint64_t count = 0;
  int level = 3;
  std::size_t frame_kib = 1024;
  double flush_interval_s = 1.0;
  bool fsync = false;
  bool overwrite = false;
  std::string note;
  double progress_s = 10.0;
  double silence_timeout_s = 5.0;
  std::string log_level = "info";
};

// Counts per topic, and lost TactileFrames per sensor (gaps in TactileFrame.sequence). Topics
// are few: a linear search over them allocates nothing once every topic has been seen.
class TopicCounts {
 public:
  void add(std::string_view topic, const zmq::message_t& payload) {
    Entry* e = find(topic);
    ++e->count;
    if (topic.starts_with(tactile::wire::kFrameTopicPrefix)) {
      if (decoder_.decode(tactile::wire::bytes_of(payload)) == tactile::wire::DecodeStatus::kOk &&
          decoder_.envelope().has_tactile_frame()) {
        const std::uint64_t seq = decoder_.envelope().tactile_frame().sequence();
        if (e->has_sequence && seq > e->last_sequence + 1) e->lost += seq - e->last_sequence - 1;
        if (!e->has_sequence || seq > e->last_sequence) e->last_sequence = seq;
        e->has_sequence = true;
      } else {
        ++e->undecodable;
      }
    }
  }
  std::string summary() const {
    std::string s;
    for (const auto& e : entries_) {
      if (!s.empty()) s += ", ";
      s += fmt::format("{} {}", e.topic, e.count);
      if (e.lost > 0) s += fmt::format(" ({} lost)", e.lost);
      if (e.undecodable > 0) s += fmt::format(" ({} undecodable)", e.undecodable);
    }
    return s.empty() ? "nothing" : s;
  }

 private:
  struct Entry {
    std::string topic;
    std::uint64_t count = 0;
    bool has_sequence = false;
    std::uint64_t last_sequence = 0;
    std::uint64_t lost = 0;
    std::uint64_t undecodable = 0;
  };
  Entry* find(std::string_view topic) {
    for (auto& e : entries_) {
      if (e.topic == topic) return &e;
    }
    entries_.push_back(Entry{std::string(topic)});
    return &entries_.back();
  }
  std::vector<Entry> entries_;
  tactile::wire::EnvelopeDecoder decoder_;
};

std::string default_output() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char name[64];
  std::strftime(name, sizeof name, "tactile-%Y%m%d-%H%M%S.tlog", &tm);
  return name;
}

std::string host_name() {
  char h[256] = {};
  if (gethostname(h, sizeof h - 1) != 0) return {};
  return h;
}

int run(Options opt) {
  tactile::util::set_log_level(tactile::util::parse_log_level(opt.log_level));
  if (opt.duration_s < 0) throw std::invalid_argument("--duration must not be negative");
  if (!(opt.flush_interval_s > 0)) throw std::invalid_argument("--flush-interval must be positive");
  if (!(opt.progress_s >= 0)) throw std::invalid_argument("--progress must not be negative");
  if (!(opt.silence_timeout_s >= 0))
    throw std::invalid_argument("--silence-timeout must not be negative");
  if (opt.raw_frames) opt.topics.emplace_back(tactile::wire::kRawTopicPrefix);
  if (opt.output.empty()) opt.output = default_output();

  tactile::recording::SourceOptions so;
  so.endpoints = opt.endpoints;
  for (const auto& c : opt.curve)
    so.curve.push_back(tactile::recording::parse_curve_source(c));
  so.client_key = opt.client_key;
  so.topics = opt.topics;

  tactile::util::install_stop_handlers();
  zmq::context_t ctx;
  Sources sources(ctx, so);

  tactile::v1::LogHeader header;
  header.set_created_ns(tactile::util::realtime_ns());
  header.set_writer(kVersion);
  header.set_host(host_name());
  header.set_note(opt.note);
  for (auto& s : sources.describe())
    *header.add_sources() = std::move(s);

  tactile::recording::LogWriterOptions wo;
  wo.level = opt.level;
  wo.frame_bytes = opt.frame_kib * 1024;
  wo.flush_interval = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(opt.flush_interval_s));
  wo.sync = opt.fsync;
  wo.overwrite = opt.overwrite;
  LogWriter writer(opt.output, header, wo);

  std::string topics;
  for (const auto& t : opt.topics)
    topics += (topics.empty() ? "" : " ") + (t.empty() ? std::string("(all)") : t);
  for (std::size_t i = 0; i < sources.size(); ++i) {
    tactile::util::log_info("subscribed to {}{} topics {}", sources.endpoint(i),
                            sources.curve(i) ? " (CURVE)" : "", topics);
  }
  tactile::util::log_info("recording to {}", opt.output);

  const std::int64_t start = tactile::util::monotonic_ns();
  const std::int64_t end =
      opt.duration_s > 0 ? start + static_cast<std::int64_t>(opt.duration_s * 1e9) : INT64_MAX;
  std::int64_t next_progress =
      opt.progress_s > 0 ? start + static_cast<std::int64_t>(opt.progress_s * 1e9) : INT64_MAX;
  // A recorder pointed at the wrong address would otherwise write an empty log and exit 0.
  std::int64_t silence_check = opt.silence_timeout_s > 0
                                   ? start + static_cast<std::int64_t>(opt.silence_timeout_s * 1e9)
                                   : INT64_MAX;
  TopicCounts counts;
  Sources::Message m;
  std::uint64_t received = 0;
  int code = 0;
  // Writes one received message; false when the log cannot take it.
  const auto keep = [&](const Sources::Message& msg) {
    const std::string_view topic(static_cast<const char*>(msg.topic.data()), msg.topic.size());
    const auto kind = topic.starts_with(tactile::wire::kRawTopicPrefix)
                          ? tactile::v1::PAYLOAD_KIND_RAW_FRAME
                          : tactile::v1::PAYLOAD_KIND_ENVELOPE;
    if (writer.append(tactile::util::realtime_ns(), topic, sources.endpoint(msg.source), kind,
                      tactile::wire::bytes_of(msg.payload)) != WriteStatus::kOk) {
      return false;
    }
    counts.add(topic, msg.payload);
    ++received;
    return true;
  };
  while (!tactile::util::stop_requested()) {
    const std::int64_t now = tactile::util::monotonic_ns();
    if (now >= end || (opt.count > 0 && received >= opt.count)) break;
    if (now >= silence_check) {
      if (const std::string silent = sources.unheard(); !silent.empty()) {
        std::fprintf(stderr, "tactile_record: nothing heard from %s within %g s\n", silent.c_str(),
                     opt.silence_timeout_s);
        code = 1;
        break;
      }
      silence_check = INT64_MAX;
    }
    if (now >= next_progress) {
      tactile::util::log_info("{} messages, {:.1f} MiB written: {}", received,
                              static_cast<double>(writer.bytes_out()) / (1 << 20),
                              counts.summary());
      next_progress = now + static_cast<std::int64_t>(opt.progress_s * 1e9);
    }
    const auto wait = std::chrono::milliseconds(std::clamp<std::int64_t>(
        (std::min({end, next_progress, silence_check}) - now) / 1000000, 1, 50));
    if (sources.receive(m, wait) && !keep(m)) {
      code = 1;
      break;
    }
    if (writer.poll() != WriteStatus::kOk) {
      code = 1;
      break;
    }
  }
  // Stopped by a signal: what had already arrived is part of the run. A recorder that fell
  // behind (a loaded machine, a slow disk) holds seconds of it in its queues, and the end of a
  // run (the publishers stopped first, as run-system does) would otherwise be lost. Only what is
  // queued: no receive waits, so publishers that go on sending end it as soon as it has caught up
  // (within a second, not after kDrainLimit). kDrainLimit bounds a publisher faster than the disk.
  if (code == 0 && tactile::util::stop_requested()) {
    constexpr std::int64_t kDrainLimit = 10'000'000'000;  // ns
    const std::int64_t drain_end = tactile::util::monotonic_ns() + kDrainLimit;
    const std::uint64_t before = received;
    while (tactile::util::monotonic_ns() < drain_end &&
           sources.receive(m, std::chrono::milliseconds(0))) {
      if (!keep(m)) {
        code = 1;
        break;
      }
    }
    if (received > before)
      tactile::util::log_info("stopping: wrote the {} messages already received",
                              received - before);
  }
  if (writer.close() != WriteStatus::kOk) code = 1;
  if (code != 0 && !writer.error().empty()) {
    tactile::util::log_error("{}", writer.error());
    std::fprintf(stderr, "tactile_record: %s\n", writer.error().c_str());
  }
  // A recording with an end of its own (--duration, --count) cut short by a signal is partial:
  // 128 + the signal's number, after what it has is written (docs/reliability.md#signals).
  if (code == 0 && (opt.duration_s > 0 || opt.count > 0))
    code = tactile::util::interrupted_exit_status();
  // A run that failed before it recorded anything leaves no header-only log behind.
  if (code != 0 && writer.records() == 0) {
    std::error_code ec;
    if (std::filesystem::remove(opt.output, ec))
      tactile::util::log_info("nothing recorded: removed {}", opt.output);
  }
  const double seconds = static_cast<double>(tactile::util::monotonic_ns() - start) * 1e-9;
  tactile::util::log_info(
      "recorded {} messages in {:.1f} s to {} ({:.2f} MiB, {:.2f} MiB before compression, {} zstd "
      "frames): {}{}",
      writer.records(), seconds, opt.output, static_cast<double>(writer.bytes_out()) / (1 << 20),
      static_cast<double>(writer.bytes_in()) / (1 << 20), writer.frames(), counts.summary(),
      sources.malformed() > 0 ? fmt::format("; {} malformed dropped", sources.malformed()) : "");
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_record");
  Options opt;
  CLI::App app{
      "Records every message of sensor_node, hand_node and rig publishers (TactileFrames, "
      "SensorStats, Events, GroundTruth; raw camera frames when asked) with its topic, source "
      "and receive time into one zstd-compressed log file (docs/recording.md). Stops cleanly on "
      "SIGINT or SIGTERM."};
  app.add_option("endpoints", opt.endpoints,
                 "publishers to subscribe to, e.g. tcp://127.0.0.1:5555 (sensor_node), the "
                 "hand_node events endpoint, tcp://127.0.0.1:5557 (rig ground truth)");
  app.add_option("--curve", opt.curve,
                 "ENDPOINT=SERVER.pub: subscribe to ENDPOINT with CURVE, trusting the publisher "
                 "whose public key is in the file (repeatable; docs/security.md)")
      ->allow_extra_args(false);
  app.add_option("--client-key", opt.client_key,
                 "this recorder's CURVE key pair (a .key file of tactile_keygen); default: a fresh "
                 "pair for this run");
  app.add_option("-o,--output", opt.output,
                 "log file to write (default tactile-YYYYmmdd-HHMMSS.tlog, UTC)");
  app.add_option("--topic", opt.topics,
                 "topic prefix to record (repeatable; \"\" records every topic)")
      ->capture_default_str()
      ->allow_extra_args(false);
  app.add_flag("--raw-frames", opt.raw_frames,
               "also record raw camera frames (topic raw/<sensor_id>, published by a sensor when "
               "asked; docs/recording.md)");
  app.add_option("--duration", opt.duration_s, "stop after this many seconds (0: until a signal)");
  app.add_option("--count", opt.count, "stop after this many messages (0: no limit)");
  app.add_option("--level", opt.level, "zstd compression level, 1 (fast) .. 19 (small)")
      ->capture_default_str();
  app.add_option("--frame-kib", opt.frame_kib,
                 "close a zstd frame once this many KiB of records are buffered")
      ->capture_default_str();
  app.add_option("--flush-interval", opt.flush_interval_s,
                 "seconds a record may wait in memory before its frame is written (what a crash "
                 "can lose)")
      ->capture_default_str();
  app.add_flag("--fsync", opt.fsync, "fdatasync the file after every frame");
  app.add_flag("--overwrite", opt.overwrite, "replace an existing output file");
  app.add_option("--note", opt.note, "free text stored in the log's header");
  app.add_option("--progress", opt.progress_s, "seconds between progress lines (0: none)")
      ->capture_default_str();
  app.add_option("--silence-timeout", opt.silence_timeout_s,
                 "exit 1, naming the endpoint, when an endpoint has sent nothing within this many "
                 "seconds of the start (the log is still closed properly; 0: wait forever)")
      ->capture_default_str();
  tactile::cli::add_log_level(app, opt.log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    if (opt.endpoints.empty() && opt.curve.empty())
      throw tactile::cli::UsageError("give at least one endpoint to subscribe to");
    return run(std::move(opt));
  });
}
