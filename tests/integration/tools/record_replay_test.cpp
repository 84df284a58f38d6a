// tactile_record and tactile_replay as processes against real publishers over real sockets: a
// recorded run holds every message; played back it gives the same bytes; its raw frames measured
// again give its TactileFrames bit for bit, and a change to the measurement is caught at the
// first frame it changes.
#include <gtest/gtest.h>
#include <signal.h>

#include <set>

#include "tactile/recording/log_writer.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/security.hpp"
#include "tactile/wire/sockets.hpp"
#include "tools_support.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using testing::Process;
using testing::TempDir;
using tools_test::await_match;
using tools_test::read_log;

constexpr int kFrames = 40;

struct FakeRun {
  std::string frames;
  std::string events;
  std::string truth;
};

// Messages fake_sensor sends with --raw --events --truth and kFrames frames.
int expected_messages() {
  int n = kFrames;                  // TactileFrames
  n += kFrames + 1 + kFrames / 25;  // raw frames and references
  for (int k = 0; k < kFrames; ++k) {
    n += k % 10 == 5 ? 1 : 0;  // events
    n += k % 5 == 0 ? 1 : 0;   // truth
  }
  return n;
}

// Runs fake_sensor and tactile_record on it until the recorder has every message.
void record_fake_run(const TempDir& dir, const std::string& bit_depth, FakeRun* run_out = nullptr) {
  Process sensor({TACTILE_FAKE_SENSOR_PATH, "--calibration", (dir / "left.yaml").string(),
                  "--frames", std::to_string(kFrames), "--raw", "--events", "--truth",
                  "--bit-depth", bit_depth, "--wait-subscriptions", "5"});
  const auto line = await_match([&] { return sensor.out_so_far(); },
                                "endpoints frames=(\\S+) events=(\\S+) truth=(\\S+)");
  ASSERT_TRUE(line) << sensor.err_so_far();
  std::smatch m;
  const std::string out = sensor.out_so_far();
  ASSERT_TRUE(std::regex_search(out, m, std::regex("frames=(\\S+) events=(\\S+) truth=(\\S+)")));
  FakeRun run{m[1], m[2], m[3]};
  if (run_out != nullptr) *run_out = run;
  const auto rec = testing::run(
      {TACTILE_RECORD_PATH, "-o", (dir / "run.tlog").string(), run.frames, run.events, run.truth,
       "--raw-frames", "--count", std::to_string(expected_messages()), "--note", "fake run"},
      60s);
  EXPECT_EQ(rec.exit_code, 0) << rec.err;
  EXPECT_FALSE(rec.timed_out);
  EXPECT_NE(rec.err.find("recorded " + std::to_string(expected_messages()) + " messages"),
            std::string::npos)
      << rec.err;
  const auto done = sensor.wait(20s);
  EXPECT_EQ(done.exit_code, 0) << done.err;
}

TEST(Record, HoldsEveryMessageOfEverySourceWithItsTopicSourceAndTime) {
  TempDir dir;
  FakeRun run;
  const std::int64_t before = util::realtime_ns();
  record_fake_run(dir, "8", &run);
  const std::int64_t after = util::realtime_ns();
  const auto log = read_log(dir / "run.tlog");
  EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
  EXPECT_EQ(log.header.format(), "tactile-log/1");
  EXPECT_EQ(log.header.note(), "fake run");
  ASSERT_EQ(log.header.sources_size(), 3);
  EXPECT_EQ(log.header.sources(0).endpoint(), run.frames);
  EXPECT_EQ(static_cast<int>(log.records.size()), expected_messages());
  EXPECT_EQ(log.per_topic.at(wire::frame_topic("left")), kFrames);
  EXPECT_EQ(log.per_topic.at(wire::raw_topic("left")), kFrames + 1 + kFrames / 25);
  EXPECT_EQ(log.per_topic.at(wire::kEventTopic), 4);
  EXPECT_EQ(log.per_topic.at(wire::kTruthTopic), 8);
  std::uint64_t next_sequence = 0;
  std::int64_t last_time = 0;
  v1::Envelope env;
  for (const auto& r : log.records) {
    EXPECT_GE(r.receive_time_ns(), before);
    EXPECT_LE(r.receive_time_ns(), after);
    EXPECT_GE(r.receive_time_ns(), last_time);  // receive times never go back on one host
    last_time = r.receive_time_ns();
    const std::string& expected_source =
        r.topic() == wire::kEventTopic ? run.events
                                       : (r.topic() == wire::kTruthTopic ? run.truth : run.frames);
    EXPECT_EQ(r.source(), expected_source) << r.topic();
    if (r.topic() == wire::raw_topic("left")) {
      EXPECT_EQ(r.kind(), v1::PAYLOAD_KIND_RAW_FRAME);
      v1::RawFrame raw;
      EXPECT_TRUE(raw.ParseFromString(r.payload()));
      continue;
    }
    EXPECT_EQ(r.kind(), v1::PAYLOAD_KIND_ENVELOPE);
    ASSERT_EQ(wire::decode(wire::bytes_of(r.payload()), env), wire::DecodeStatus::kOk);
    if (r.topic() == wire::frame_topic("left")) {
      ASSERT_TRUE(env.has_tactile_frame());
      EXPECT_EQ(env.tactile_frame().sequence(), next_sequence++);
    }
  }
}

TEST(Remeasure, RecordedRawFramesGiveTheRecordedTactileFramesBitForBit) {
  for (const std::string depth : {"8", "16"}) {
    TempDir dir;
    record_fake_run(dir, depth);
    const auto r = testing::run({TACTILE_REPLAY_PATH, "--remeasure", (dir / "left.yaml").string(),
                                 (dir / "run.tlog").string()},
                                60s);
    EXPECT_EQ(r.exit_code, 0) << depth << "-bit: " << r.out << r.err;
    EXPECT_NE(r.out.find("left: " + std::to_string(kFrames) + " frames measured again, " +
                         std::to_string(kFrames) + " identical bit for bit, 0 differ"),
              std::string::npos)
        << r.out << r.err;
  }
}

TEST(Remeasure, AChangedMeasurementIsReportedAtItsFirstDifference) {
  TempDir dir;
  record_fake_run(dir, "8");
  const auto r = testing::run({TACTILE_REPLAY_PATH, (dir / "run.tlog").string(), "--remeasure",
                               (dir / "left.yaml").string(), "--estimator", "plain"},
                              60s);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("tactile_replay: first difference: sensor left, TactileFrame "),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(std::regex_search(r.err, std::regex("element \\d+ \\(id \\d+\\) \\w+: recorded "
                                                  "\\S+ \\(0x[0-9a-f]{16}\\), remeasured")))
      << r.err;
  // A calibration that differs from the recorded one is caught too.
  std::string cal = util::read_file(dir / "left.yaml");
  const auto at = cal.find("noise_floor: ");
  ASSERT_NE(at, std::string::npos);
  cal.replace(at, std::string("noise_floor: ").size(), "noise_floor: 1");  // e.g. 4 -> 14
  util::write_file_atomic(dir / "changed.yaml", cal);
  const auto c = testing::run({TACTILE_REPLAY_PATH, (dir / "run.tlog").string(), "--remeasure",
                               (dir / "changed.yaml").string()},
                              60s);
  EXPECT_EQ(c.exit_code, 1) << c.out << c.err;
  EXPECT_NE(c.err.find("first difference: sensor left"), std::string::npos) << c.err;
}

TEST(Remeasure, ALogWithoutRawFramesSaysWhatIsMissing) {
  TempDir dir;
  record_fake_run(dir, "8");
  // Keep everything but the raw frames.
  {
    recording::LogReader in(dir / "run.tlog");
    recording::LogWriter out(dir / "noraw.tlog", in.header(), {});
    v1::LogRecord rec;
    while (in.next(rec) == recording::ReadStatus::kRecord) {
      if (rec.kind() == v1::PAYLOAD_KIND_RAW_FRAME) continue;
      ASSERT_EQ(out.append(rec.receive_time_ns(), rec.topic(), rec.source(), rec.kind(),
                           wire::bytes_of(rec.payload())),
                recording::WriteStatus::kOk);
    }
  }
  const auto r = testing::run({TACTILE_REPLAY_PATH, (dir / "noraw.tlog").string(), "--remeasure",
                               (dir / "left.yaml").string()},
                              60s);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("40 measured frames without a raw frame"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("no frame could be measured again"), std::string::npos) << r.err;
}

// Reads the replayer's bound endpoint from its log line.
std::string replay_endpoint(Process& p) {
  const auto ep = await_match([&] { return p.err_so_far(); }, "publishing on (tcp://\\S+)");
  return ep.value_or("");
}

TEST(Replay, AsFastAsPossibleGivesEveryRecordedMessageByteForByte) {
  TempDir dir;
  record_fake_run(dir, "8");
  const auto log = read_log(dir / "run.tlog");
  Process replay({TACTILE_REPLAY_PATH, (dir / "run.tlog").string(), "--publish",
                  "tcp://127.0.0.1:*", "--as-fast-as-possible", "--wait-subscriptions", "1",
                  "--topic", wire::kFrameTopicPrefix, "--topic", wire::kEventTopic});
  const std::string ep = replay_endpoint(replay);
  ASSERT_FALSE(ep.empty()) << replay.err_so_far();
  zmq::context_t ctx;
  wire::Subscriber sub(ctx, {ep}, {""});
  std::vector<const v1::LogRecord*> wanted;
  for (const auto& r : log.records) {
    if (r.topic().starts_with(wire::kFrameTopicPrefix) || r.topic() == wire::kEventTopic)
      wanted.push_back(&r);
  }
  ASSERT_EQ(wanted.size(), static_cast<std::size_t>(kFrames + 4));
  wire::TopicMessage m;
  std::size_t got = 0;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (got < wanted.size() && std::chrono::steady_clock::now() < deadline) {
    if (!sub.receive(m, 100ms)) continue;
    ASSERT_EQ(m.topic, wanted[got]->topic());
    ASSERT_EQ(std::string(m.payload.begin(), m.payload.end()), wanted[got]->payload())
        << "message " << got;
    ++got;
  }
  EXPECT_EQ(got, wanted.size());
  const auto done = replay.wait(20s);
  EXPECT_EQ(done.exit_code, 0) << done.err;
  EXPECT_NE(done.err.find("replayed 44 messages"), std::string::npos) << done.err;
  EXPECT_FALSE(sub.receive(m, 50ms));  // nothing filtered out came through
}

// A log whose records are 50 ms apart plays back no faster than that at --speed 1, and
// proportionally faster at --speed 10.
TEST(Replay, KeepsTheRecordedPaceScaledBySpeed) {
  TempDir dir;
  {
    recording::LogWriter w(dir / "paced.tlog", v1::LogHeader{}, {});
    v1::Envelope env;
    std::string buf;
    for (int i = 0; i < 11; ++i) {
      auto* e = env.mutable_event();
      e->set_time_ns(i);
      e->set_kind(v1::EVENT_KIND_PHASE);
      wire::encode(env, buf);
      ASSERT_EQ(w.append(1'000'000'000LL + i * 50'000'000LL, wire::kEventTopic, "x",
                         v1::PAYLOAD_KIND_ENVELOPE, wire::bytes_of(buf)),
                recording::WriteStatus::kOk);
    }
  }
  for (const auto& [speed, least_ms] : {std::pair<std::string, int>{"1", 500}, {"10", 50}}) {
    Process replay({TACTILE_REPLAY_PATH, (dir / "paced.tlog").string(), "--publish",
                    "tcp://127.0.0.1:*", "--speed", speed, "--wait-subscriptions", "1"});
    const std::string ep = replay_endpoint(replay);
    ASSERT_FALSE(ep.empty());
    zmq::context_t ctx;
    wire::Subscriber sub(ctx, {ep}, {wire::kEventTopic});
    wire::TopicMessage m;
    int got = 0;
    std::chrono::steady_clock::time_point first;
    std::chrono::steady_clock::time_point last;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (got < 11 && std::chrono::steady_clock::now() < deadline) {
      if (!sub.receive(m, 100ms)) continue;
      last = std::chrono::steady_clock::now();
      if (got == 0) first = last;
      ++got;
    }
    EXPECT_EQ(got, 11);
    EXPECT_GE(std::chrono::duration_cast<std::chrono::milliseconds>(last - first).count(),
              least_ms - 5)
        << "speed " << speed;
    EXPECT_EQ(replay.wait(20s).exit_code, 0);
  }
}

// Publishes `event` on `pub` every 5 ms until the recorder writing `path` has a record on disk
// past the log's header (it joins late: pace by polling; bounded).
void publish_until_recorded(wire::Publisher& pub, const std::filesystem::path& path,
                            const std::string& event) {
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  std::uintmax_t header_size = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    pub.send(wire::kEventTopic, wire::bytes_of(event));
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && header_size == 0) header_size = size;
    if (!ec && size > header_size && header_size > 0) return;
    std::this_thread::sleep_for(5ms);
  }
}

// A signal ends a recording cleanly with what it got: status 0 when the signal is its end, 128 +
// the signal's number when it cut a --duration short (docs/reliability.md#signals).
TEST(Record, StopsCleanlyOnSignalsAndKeepsWhatItGot) {
  TempDir dir;
  zmq::context_t ctx;
  wire::Publisher pub(ctx, "tcp://127.0.0.1:*");
  v1::Envelope env;
  env.mutable_event()->set_kind(v1::EVENT_KIND_TOUCH);
  std::string buf;
  wire::encode(env, buf);
  for (const int sig : {SIGINT, SIGTERM}) {
    for (const bool with_duration : {false, true}) {
      const auto path =
          dir / ("sig" + std::to_string(sig) + (with_duration ? "-duration" : "") + ".tlog");
      std::vector<std::string> argv{TACTILE_RECORD_PATH, "-o",  path.string(), pub.endpoint(),
                                    "--flush-interval",  "0.05"};
      if (with_duration) argv.insert(argv.end(), {"--duration", "60"});
      Process rec(argv);
      publish_until_recorded(pub, path, buf);
      rec.signal(sig);
      const auto r = rec.wait(20s);
      EXPECT_EQ(r.exit_code, with_duration ? 128 + sig : 0) << r.err;
      const auto log = read_log(path);
      EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
      EXPECT_GE(log.per_topic.at(wire::kEventTopic), 1);
    }
  }
}

// A recorder that fell behind (here: the slowest compression, on large messages) still holds
// messages that had arrived when the signal came: it writes them before it closes the log.
TEST(Record, OnASignalItFirstWritesWhatHadAlreadyArrived) {
  TempDir dir;
  zmq::context_t ctx;
  wire::Publisher pub(ctx, "tcp://127.0.0.1:*");
  const auto path = dir / "behind.tlog";
  Process rec({TACTILE_RECORD_PATH, "-o", path.string(), pub.endpoint(), "--level", "19",
               "--flush-interval", "0.05", "--topic", "big", "--topic", wire::kEventTopic});
  v1::Envelope env;
  env.mutable_event()->set_kind(v1::EVENT_KIND_TOUCH);
  std::string event;
  wire::encode(env, event);
  publish_until_recorded(pub, path, event);
  // 60 messages of 256 KiB that compress slowly (a counter's bytes, like an image's texture).
  constexpr int kBig = 60;
  std::vector<std::uint8_t> big(256 * 1024);
  std::uint32_t x = 12345;
  for (int k = 0; k < kBig; ++k) {
    for (auto& b : big) {
      x = x * 1664525U + 1013904223U;
      b = static_cast<std::uint8_t>((x >> 24) & 0x3F);
    }
    pub.send("big", big);
  }
  std::this_thread::sleep_for(200ms);  // on the wire to the recorder, not yet written
  rec.signal(SIGINT);
  const auto r = rec.wait(60s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto log = read_log(path);
  EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
  ASSERT_TRUE(log.per_topic.contains("big")) << r.err;
  EXPECT_EQ(log.per_topic.at("big"), kBig) << r.err;
}

// Publishes an event on `pub` every 5 ms while `rec` runs (bounded).
void publish_while_running(wire::Publisher& pub, Process& rec) {
  v1::Envelope env;
  env.mutable_event()->set_kind(v1::EVENT_KIND_TOUCH);
  std::string buf;
  wire::encode(env, buf);
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (rec.running() && std::chrono::steady_clock::now() < deadline) {
    pub.send(wire::kEventTopic, wire::bytes_of(buf));
    std::this_thread::sleep_for(5ms);
  }
}

// Ctrl-C while the publisher goes on sending: what is queued is written, nothing more is waited
// for, and it ends within a second (it drained for up to 10 s before).
TEST(Record, ASignalEndsItWithinASecondWhileThePublisherGoesOnSending) {
  TempDir dir;
  zmq::context_t ctx;
  wire::Publisher pub(ctx, "tcp://127.0.0.1:*");
  const auto path = dir / "busy.tlog";
  Process rec(
      {TACTILE_RECORD_PATH, "-o", path.string(), pub.endpoint(), "--flush-interval", "0.05"});
  v1::Envelope env;
  env.mutable_event()->set_kind(v1::EVENT_KIND_TOUCH);
  std::string buf;
  wire::encode(env, buf);
  publish_until_recorded(pub, path, buf);
  const auto signalled = std::chrono::steady_clock::now();
  rec.signal(SIGINT);
  publish_while_running(pub, rec);
  const auto ended = std::chrono::steady_clock::now();
  const auto r = rec.wait(10s);
  EXPECT_EQ(r.exit_code, 0) << r.err;  // no --duration: a signal is its normal end
  EXPECT_LT(ended - signalled, 1s) << r.err;
  const auto log = read_log(path);
  EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
  EXPECT_GE(log.per_topic.at(wire::kEventTopic), 1);
}

// Nobody publishing: it fails (silence) before it recorded anything and leaves no log behind.
TEST(Record, FailingBeforeAnyRecordLeavesNoFile) {
  TempDir dir;
  zmq::context_t ctx;
  wire::Publisher silent(ctx, "tcp://127.0.0.1:*");
  const auto path = dir / "nothing.tlog";
  const auto r = testing::run(
      {TACTILE_RECORD_PATH, "-o", path.string(), silent.endpoint(), "--silence-timeout", "0.5"},
      20s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("nothing heard from"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path)) << r.err;
}

TEST(Record, AnEndpointSilentForTheSilenceTimeoutEndsItNonZeroNamingThatEndpoint) {
  TempDir dir;
  zmq::context_t ctx;
  wire::Publisher talking(ctx, "tcp://127.0.0.1:*");
  wire::Publisher silent(ctx, "tcp://127.0.0.1:*");  // bound, so the connection succeeds
  const auto path = dir / "silent.tlog";
  const auto start = std::chrono::steady_clock::now();
  Process rec({TACTILE_RECORD_PATH, "-o", path.string(), talking.endpoint(), silent.endpoint(),
               "--silence-timeout", "1", "--flush-interval", "0.05"});
  publish_while_running(talking, rec);
  const auto r = rec.wait(10s);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(r.timed_out);
  EXPECT_GE(elapsed, 1s);
  EXPECT_LT(elapsed, 8s);  // the timeout and a margin for a loaded machine
  EXPECT_NE(r.err.find("tactile_record: nothing heard from " + silent.endpoint() + " within 1 s\n"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("nothing heard from " + talking.endpoint()), std::string::npos) << r.err;
  // The log is whole and holds what the other endpoint sent.
  const auto log = read_log(path);
  EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
  EXPECT_GE(log.per_topic.at(wire::kEventTopic), 1);

  // Every endpoint heard within the timeout: it records on to the end of --duration.
  const auto both = dir / "both.tlog";
  Process rec2({TACTILE_RECORD_PATH, "-o", both.string(), talking.endpoint(), "--duration", "2",
                "--silence-timeout", "1"});
  publish_while_running(talking, rec2);
  const auto r2 = rec2.wait(10s);
  EXPECT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(r2.err.find("nothing heard"), std::string::npos) << r2.err;
  EXPECT_EQ(read_log(both).end, recording::ReadStatus::kEnd);
}

TEST(Record, KilledMidRunLeavesALogThatReadsUpToItsLastWholeFrame) {
  TempDir dir;
  zmq::context_t ctx;
  wire::Publisher pub(ctx, "tcp://127.0.0.1:*");
  const auto path = dir / "killed.tlog";
  Process rec({TACTILE_RECORD_PATH, "-o", path.string(), pub.endpoint(), "--flush-interval", "0.01",
               "--frame-kib", "4"});
  std::string payload(3000, 'z');
  v1::Envelope env;
  env.mutable_event()->set_text(payload);
  std::string buf;
  wire::encode(env, buf);
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (std::chrono::steady_clock::now() < deadline) {
    pub.send(wire::kEventTopic, wire::bytes_of(buf));
    std::error_code ec;
    if (std::filesystem::file_size(path, ec) > 20000 && !ec) break;
    std::this_thread::sleep_for(1ms);
  }
  rec.signal(SIGKILL);
  rec.wait(10s);
  const auto log = read_log(path);
  EXPECT_NE(log.end, recording::ReadStatus::kCorrupt);
  EXPECT_GE(log.per_topic.at(wire::kEventTopic), 3);
  for (const auto& r : log.records)
    EXPECT_EQ(r.payload(), buf);
}

TEST(Record, CurveSubscriptionTakesOnlyTheKeyHolder) {
  if (!wire::curve_available()) GTEST_FAIL() << "libzmq without CURVE";
  TempDir dir;
  wire::write_key_files(dir.path(), "sensor", wire::generate_keypair());
  wire::write_key_files(dir.path(), "other", wire::generate_keypair());
  wire::write_key_files(dir.path(), "recorder", wire::generate_keypair());
  zmq::context_t ctx;
  const wire::ServerSecurity sec{wire::load_key_pair(dir / "sensor.key"), {}};
  wire::Publisher pub(ctx, "tcp://127.0.0.1:*", &sec);
  const auto good = dir / "good.tlog";
  const auto bad = dir / "bad.tlog";
  Process rec_good({TACTILE_RECORD_PATH, "-o", good.string(), "--curve",
                    pub.endpoint() + "=" + (dir / "sensor.pub").string(), "--client-key",
                    (dir / "recorder.key").string(), "--count", "5"});
  // Refused, it hears nothing: it must wait for its signal, not give up on the silence.
  Process rec_bad({TACTILE_RECORD_PATH, "-o", bad.string(), "--curve",
                   pub.endpoint() + "=" + (dir / "other.pub").string(), "--flush-interval", "0.01",
                   "--silence-timeout", "0"});
  v1::Envelope env;
  env.mutable_event()->set_kind(v1::EVENT_KIND_OVER);
  std::string buf;
  wire::encode(env, buf);
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (rec_good.running() && std::chrono::steady_clock::now() < deadline) {
    pub.send(wire::kEventTopic, wire::bytes_of(buf));
    std::this_thread::sleep_for(5ms);
  }
  const auto r = rec_good.wait(10s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("(CURVE)"), std::string::npos) << r.err;
  EXPECT_EQ(read_log(good).per_topic.at(wire::kEventTopic), 5);
  rec_bad.signal(SIGTERM);
  EXPECT_EQ(rec_bad.wait(10s).exit_code, 0);
  EXPECT_TRUE(read_log(bad).records.empty());
}

TEST(Tools, BadOptionsAndFilesGiveOneClearLine) {
  TempDir dir;
  auto one_line = [](const testing::ProcessResult& r) {
    return std::count(r.err.begin(), r.err.end(), '\n') == 1;
  };
  auto r = testing::run({TACTILE_RECORD_PATH});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tactile_record: give at least one endpoint"), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r)) << r.err;
  r = testing::run({TACTILE_RECORD_PATH, "tcp://127.0.0.1:1", "--level", "x"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r)) << r.err;
  r = testing::run({TACTILE_RECORD_PATH, "nonsense://x", "-o", (dir / "a.tlog").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot connect to 'nonsense://x'"), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r)) << r.err;
  util::write_file_atomic(dir / "exists.tlog", "x");
  r = testing::run(
      {TACTILE_RECORD_PATH, "tcp://127.0.0.1:1", "-o", (dir / "exists.tlog").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("exists.tlog: exists already"), std::string::npos) << r.err;
  r = testing::run({TACTILE_RECORD_PATH, "--curve",
                    "tcp://127.0.0.1:1=" + (dir / "no.pub").string(), "-o",
                    (dir / "b.tlog").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no.pub"), std::string::npos) << r.err;
  // One publisher named plain and with --curve: refused before anything is recorded.
  wire::write_key_files(dir.path(), "hand", wire::generate_keypair());
  r = testing::run({TACTILE_RECORD_PATH, "tcp://127.0.0.1:1", "--curve",
                    "tcp://127.0.0.1:1=" + (dir / "hand.pub").string(), "-o",
                    (dir / "c.tlog").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("'tcp://127.0.0.1:1' is given twice"), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r)) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "c.tlog"));

  r = testing::run({TACTILE_REPLAY_PATH, (dir / "missing.tlog").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.tlog: cannot open"), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r)) << r.err;
  r = testing::run({TACTILE_REPLAY_PATH, (dir / "exists.tlog").string(), "--info"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("not a tactile log"), std::string::npos) << r.err;
  r = testing::run({TACTILE_REPLAY_PATH});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r)) << r.err;
  for (const char* tool : {TACTILE_RECORD_PATH, TACTILE_REPLAY_PATH}) {
    r = testing::run({tool, "--help"});
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("Usage"), std::string::npos);
  }
}

TEST(Replay, InfoDescribesTheLogAndStopsOnSignalWhileWaiting) {
  TempDir dir;
  record_fake_run(dir, "8");
  auto r = testing::run({TACTILE_REPLAY_PATH, (dir / "run.tlog").string(), "--info"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tactile-log/1 written by tactile_record"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("note: fake run"), std::string::npos) << r.out;
  EXPECT_TRUE(std::regex_search(r.out, std::regex(wire::frame_topic("left") + "\\s+40")));
  EXPECT_NE(r.out.find("end: end"), std::string::npos) << r.out;
  // Cut it: --info reports the truncated tail and still succeeds.
  std::string bytes = util::read_file(dir / "run.tlog");
  bytes.resize(bytes.size() - 10);
  util::write_file_atomic(dir / "cut.tlog", bytes);
  r = testing::run({TACTILE_REPLAY_PATH, (dir / "cut.tlog").string(), "--info"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("end: truncated: "), std::string::npos) << r.out;

  Process waiting({TACTILE_REPLAY_PATH, (dir / "run.tlog").string(), "--publish",
                   "tcp://127.0.0.1:*", "--wait-subscriptions", "1"});
  ASSERT_FALSE(replay_endpoint(waiting).empty());
  waiting.signal(SIGTERM);
  // Stopped before it played the log: 128 + SIGTERM (docs/reliability.md#signals).
  EXPECT_EQ(waiting.wait(10s).exit_code, 143);
}

}  // namespace
}  // namespace tactile
