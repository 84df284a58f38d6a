// The log format (docs/recording.md): records round-trip through whole zstd frames, a file cut at
// any byte keeps every record of the whole frames before the cut and reports the tail, and a
// damaged frame is reported with the records before it kept.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "tactile/recording/log_reader.hpp"
#include "tactile/recording/log_writer.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/random.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile::recording {
namespace {

using testing::TempDir;

struct Written {
  std::int64_t time_ns;
  std::string topic;
  std::string source;
  v1::PayloadKind kind;
  std::string payload;
};

// Records of varied sizes, some incompressible.
std::vector<Written> make_records(std::size_t n, std::uint64_t seed,
                                  std::size_t max_payload = 3000) {
  util::Random rng(seed);
  std::vector<Written> out;
  for (std::size_t i = 0; i < n; ++i) {
    Written w;
    w.time_ns = 1'700'000'000'000'000'000 + static_cast<std::int64_t>(i) * 10'000'000;
    w.topic = i % 3 == 0 ? wire::frame_topic("left")
                         : (i % 3 == 1 ? wire::kEventTopic : wire::raw_topic("right"));
    w.source = i % 2 == 0 ? "tcp://127.0.0.1:5555" : "tcp://127.0.0.1:5558";
    w.kind = w.topic.starts_with(wire::kRawTopicPrefix) ? v1::PAYLOAD_KIND_RAW_FRAME
                                                        : v1::PAYLOAD_KIND_ENVELOPE;
    w.payload.resize(rng.below(max_payload));
    for (std::size_t k = 0; k < w.payload.size(); ++k)
      w.payload[k] = static_cast<char>(k % 7 == 0 ? rng.below(256) : k % 13);
    out.push_back(std::move(w));
  }
  return out;
}

v1::LogHeader test_header() {
  v1::LogHeader h;
  h.set_created_ns(42);
  h.set_writer("log_format_test");
  h.set_note("a note");
  auto* s = h.add_sources();
  s->set_endpoint("tcp://127.0.0.1:5555");
  s->add_topics(wire::kFrameTopicPrefix);
  return h;
}

// Writes the records; returns the file size after each flushed frame (frame boundaries).
std::vector<std::uint64_t> write_log(const std::filesystem::path& path,
                                     const std::vector<Written>& records,
                                     std::size_t records_per_frame) {
  LogWriterOptions o;
  o.frame_bytes = 1 << 20;
  LogWriter w(path, test_header(), o);
  std::vector<std::uint64_t> boundaries{w.bytes_out()};
  for (std::size_t i = 0; i < records.size(); ++i) {
    const Written& r = records[i];
    EXPECT_EQ(w.append(r.time_ns, r.topic, r.source, r.kind, wire::bytes_of(r.payload)),
              WriteStatus::kOk);
    if ((i + 1) % records_per_frame == 0) {
      EXPECT_EQ(w.flush(), WriteStatus::kOk);
      boundaries.push_back(w.bytes_out());
    }
  }
  EXPECT_EQ(w.close(), WriteStatus::kOk);
  if (boundaries.back() != w.bytes_out()) boundaries.push_back(w.bytes_out());
  EXPECT_EQ(w.records(), records.size());
  return boundaries;
}

void expect_equal(const v1::LogRecord& got, const Written& want) {
  EXPECT_EQ(got.receive_time_ns(), want.time_ns);
  EXPECT_EQ(got.topic(), want.topic);
  EXPECT_EQ(got.source(), want.source);
  EXPECT_EQ(got.kind(), want.kind);
  EXPECT_EQ(got.payload(), want.payload);
  EXPECT_FALSE(got.has_header());
}

TEST(LogFormat, RecordsRoundTripThroughWholeFrames) {
  TempDir dir;
  const auto records = make_records(500, 1);
  const auto path = dir / "a.tlog";
  const auto boundaries = write_log(path, records, 37);
  EXPECT_EQ(std::filesystem::file_size(path), boundaries.back());

  LogReader r(path);
  EXPECT_EQ(r.header().format(), "tactile-log/1");
  EXPECT_EQ(r.header().writer(), "log_format_test");
  EXPECT_EQ(r.header().note(), "a note");
  ASSERT_EQ(r.header().sources_size(), 1);
  EXPECT_EQ(r.header().sources(0).endpoint(), "tcp://127.0.0.1:5555");
  v1::LogRecord rec;
  for (const auto& want : records) {
    ASSERT_EQ(r.next(rec), ReadStatus::kRecord);
    expect_equal(rec, want);
  }
  EXPECT_EQ(r.next(rec), ReadStatus::kEnd);
  EXPECT_EQ(r.next(rec), ReadStatus::kEnd);
  EXPECT_TRUE(r.problem().empty());
  EXPECT_EQ(r.records(), records.size());
  EXPECT_EQ(r.position(), boundaries.back());
}

TEST(LogFormat, LargeRecordsAndAutomaticFrames) {
  TempDir dir;
  const auto path = dir / "big.tlog";
  LogWriterOptions o;
  o.frame_bytes = 64 << 10;
  std::vector<std::string> payloads;
  util::Random rng(3);
  {
    LogWriter w(path, test_header(), o);
    for (int i = 0; i < 12; ++i) {
      std::string p(static_cast<std::size_t>(300000 + i * 1000), '\0');
      for (auto& c : p)
        c = static_cast<char>(rng.below(256));
      ASSERT_EQ(
          w.append(i, wire::raw_topic("left"), "s", v1::PAYLOAD_KIND_RAW_FRAME, wire::bytes_of(p)),
          WriteStatus::kOk);
      // Each record is larger than a frame: it is written at once, alone.
      EXPECT_EQ(w.buffered_bytes(), 0U);
      payloads.push_back(std::move(p));
    }
    EXPECT_EQ(w.frames(), 13U);  // the header's and one per record
  }
  LogReader r(path);
  v1::LogRecord rec;
  for (const auto& p : payloads) {
    ASSERT_EQ(r.next(rec), ReadStatus::kRecord);
    EXPECT_EQ(rec.payload(), p);
  }
  EXPECT_EQ(r.next(rec), ReadStatus::kEnd);
}

// Cut the file at every byte near a frame boundary and at many in between: the reader keeps exactly
// the records of the whole frames before the cut, reports a truncated tail unless the cut falls on
// a frame boundary, and never fails in any other way.
TEST(LogFormat, EveryTruncationKeepsTheWholeFramesBeforeIt) {
  TempDir dir;
  const auto records = make_records(60, 2, 160);
  const auto full = dir / "full.tlog";
  const auto boundaries = write_log(full, records, 10);
  ASSERT_EQ(boundaries.size(), 7U);  // header frame + 6 frames of 10 records
  const std::string bytes_all = util::read_file(full);
  const auto cut = dir / "cut.tlog";
  auto near_boundary = [&](std::size_t size) {
    for (const auto b : boundaries) {
      if (size + 24 >= b && size <= b + 24) return true;
    }
    return false;
  };
  // Every byte near a frame boundary, every 7th elsewhere.
  for (std::size_t size = 0; size < bytes_all.size(); size += near_boundary(size) ? 1 : 7) {
    {
      std::ofstream out(cut, std::ios::binary | std::ios::trunc);
      out.write(bytes_all.data(), static_cast<std::streamsize>(size));
    }
    if (size < boundaries[0]) {
      EXPECT_THROW({ LogReader r(cut); }, std::runtime_error) << size;
      continue;
    }
    LogReader r(cut);
    std::size_t whole = 0;  // frames of records wholly before the cut
    while (whole + 1 < boundaries.size() && boundaries[whole + 1] <= size)
      ++whole;
    v1::LogRecord rec;
    std::size_t n = 0;
    ReadStatus s;
    while ((s = r.next(rec)) == ReadStatus::kRecord) {
      ASSERT_LT(n, records.size());
      expect_equal(rec, records[n]);
      ++n;
    }
    EXPECT_EQ(n, whole * 10) << "cut at " << size;
    const bool on_boundary = boundaries[whole] == size;
    EXPECT_EQ(s, on_boundary ? ReadStatus::kEnd : ReadStatus::kTruncated) << "cut at " << size;
    if (!on_boundary) {
      EXPECT_NE(r.problem().find("truncated tail"), std::string::npos) << r.problem();
      EXPECT_NE(r.problem().find("from byte " + std::to_string(boundaries[whole])),
                std::string::npos)
          << r.problem();
    }
  }
}

TEST(LogFormat, DamagedFrameIsReportedAfterTheRecordsBeforeIt) {
  TempDir dir;
  const auto records = make_records(40, 4);
  const auto path = dir / "d.tlog";
  const auto boundaries = write_log(path, records, 10);
  std::string b = util::read_file(path);
  // Flip a byte in the middle of the third frame of records.
  const std::size_t at = (boundaries[3] + boundaries[4]) / 2;
  b[at] = static_cast<char>(b[at] ^ 0x5A);
  util::write_file_atomic(path, b);
  LogReader r(path);
  v1::LogRecord rec;
  std::size_t n = 0;
  ReadStatus s;
  while ((s = r.next(rec)) == ReadStatus::kRecord)
    ++n;
  EXPECT_EQ(s, ReadStatus::kCorrupt);
  EXPECT_EQ(n, 30U);
  EXPECT_NE(r.problem().find("at byte " + std::to_string(boundaries[3])), std::string::npos)
      << r.problem();
}

TEST(LogFormat, RefusesWhatIsNotALog) {
  TempDir dir;
  util::write_file_atomic(dir / "empty.tlog", "");
  util::write_file_atomic(dir / "text.tlog", "hello, this is not a log\n");
  try {
    LogReader r(dir / "empty.tlog");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("empty.tlog: empty file"), std::string::npos) << e.what();
  }
  try {
    LogReader r(dir / "text.tlog");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("text.tlog: not a tactile log"), std::string::npos)
        << e.what();
  }
  try {
    LogReader r(dir / "missing.tlog");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.tlog: cannot open"), std::string::npos)
        << e.what();
  }
}

TEST(LogFormat, RefusesToOverwriteUnlessAsked) {
  TempDir dir;
  const auto path = dir / "x.tlog";
  { LogWriter w(path, test_header(), {}); }
  try {
    LogWriter w(path, test_header(), {});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("x.tlog: exists already"), std::string::npos) << e.what();
  }
  LogWriterOptions o;
  o.overwrite = true;
  EXPECT_NO_THROW({ LogWriter w(path, test_header(), o); });
  o.level = 0;
  EXPECT_THROW({ LogWriter w(dir / "y.tlog", test_header(), o); }, std::invalid_argument);
}

TEST(LogFormat, HeaderIsOnDiskBeforeAnyRecordAndRecordsAfterTheFlushInterval) {
  TempDir dir;
  const auto path = dir / "live.tlog";
  LogWriterOptions o;
  o.flush_interval = std::chrono::milliseconds(20);
  LogWriter w(path, test_header(), o);
  const auto header_size = std::filesystem::file_size(path);
  EXPECT_GT(header_size, 0U);
  { LogReader r(path); }
  const std::string payload = "payload";
  ASSERT_EQ(w.append(1, wire::kEventTopic, "s", v1::PAYLOAD_KIND_ENVELOPE, wire::bytes_of(payload)),
            WriteStatus::kOk);
  ASSERT_EQ(w.poll(), WriteStatus::kOk);
  EXPECT_EQ(std::filesystem::file_size(path), header_size);  // still buffered
  // Poll until the interval has passed (bounded); then the frame is on disk.
  const std::int64_t deadline = util::monotonic_ns() + 2'000'000'000;
  while (w.buffered_bytes() > 0 && util::monotonic_ns() < deadline)
    ASSERT_EQ(w.poll(), WriteStatus::kOk);
  EXPECT_EQ(w.buffered_bytes(), 0U);
  EXPECT_GT(std::filesystem::file_size(path), header_size);
  LogReader r(path);
  v1::LogRecord rec;
  ASSERT_EQ(r.next(rec), ReadStatus::kRecord);
  EXPECT_EQ(rec.payload(), payload);
  EXPECT_EQ(r.next(rec), ReadStatus::kEnd);
}

}  // namespace
}  // namespace tactile::recording
