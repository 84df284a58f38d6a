// The MCAP writer and the log export, read back by a parser written here from the spec
// (https://mcap.dev/spec), independent of the writer's code: every record framed, the magic at
// both ends, the CRCs, the footer -> summary -> chunk index -> chunk -> message index path a
// reader uses, the statistics, the metadata index -> metadata path, and the schemas as
// FileDescriptorSets that rebuild the messages and name every field as protoc does.
#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/descriptor_database.h>
#include <google/protobuf/dynamic_message.h>
#include <gtest/gtest.h>
#include <zstd.h>

#include <cctype>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "process.hpp"
#include "tactile/mcap/export.hpp"
#include "tactile/mcap/writer.hpp"
#include "tactile/recording/log_writer.hpp"
#include "tactile/util/files.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile {
namespace {

using testing::TempDir;

const std::string kMagic{"\x89MCAP0\r\n", 8};

struct Cursor {
  std::string_view s;
  std::size_t pos = 0;
  template <typename T>
  T get() {
    if (pos + sizeof(T) > s.size()) throw std::out_of_range("past the end");
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      v |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(s[pos + i])) << (8 * i);
    pos += sizeof(T);
    return static_cast<T>(v);
  }
  std::string_view bytes(std::size_t n) {
    if (pos + n > s.size()) throw std::out_of_range("past the end");
    const auto out = s.substr(pos, n);
    pos += n;
    return out;
  }
  std::string_view string() { return bytes(get<std::uint32_t>()); }
  bool done() const { return pos == s.size(); }
};

struct Record {
  std::uint8_t opcode;
  std::uint64_t offset;  // of the opcode, from the start of what was parsed
  std::string_view content;
};

std::vector<Record> records(std::string_view s) {
  std::vector<Record> out;
  Cursor c{s};
  while (!c.done()) {
    Record r;
    r.offset = c.pos;
    r.opcode = c.get<std::uint8_t>();
    r.content = c.bytes(c.get<std::uint64_t>());
    out.push_back(r);
  }
  return out;
}

std::uint32_t reference_crc(std::string_view s) {  // bitwise, not the writer's table
  std::uint32_t crc = 0xFFFFFFFF;
  for (const char ch : s) {
    crc ^= static_cast<std::uint8_t>(ch);
    for (int k = 0; k < 8; ++k)
      crc = (crc >> 1) ^ (0xEDB88320U & (0U - (crc & 1)));
  }
  return ~crc;
}

struct Message {
  std::uint16_t channel;
  std::uint32_t sequence;
  std::uint64_t log_time;
  std::uint64_t publish_time;
  std::string data;
};

// Reads a whole file the way an indexed reader does and checks every rule on the way.
struct Parsed {
  std::map<std::uint16_t, std::pair<std::string, std::string>> schemas;     // id -> name, data
  std::map<std::uint16_t, std::pair<std::uint16_t, std::string>> channels;  // id -> schema, topic
  std::vector<Message> messages;                                            // in chunk-index order
  std::uint64_t message_count = 0;
  std::uint32_t chunk_count = 0;
  std::map<std::uint16_t, std::uint64_t> channel_counts;
  std::vector<std::string> compressions;
  std::uint32_t metadata_count = 0;                                    // from the statistics
  std::map<std::string, std::map<std::string, std::string>> metadata;  // by its index
};

std::map<std::string, std::string> parse_map(std::string_view bytes) {
  std::map<std::string, std::string> out;
  Cursor c{bytes};
  while (!c.done()) {
    const auto key = std::string(c.string());
    EXPECT_TRUE(out.emplace(key, std::string(c.string())).second) << "key twice: " << key;
  }
  return out;
}

Parsed parse(const std::string& file) {
  Parsed p;
  EXPECT_EQ(file.substr(0, 8), kMagic);
  EXPECT_EQ(file.substr(file.size() - 8), kMagic);
  const auto all = records(std::string_view(file).substr(8, file.size() - 16));
  EXPECT_EQ(all.front().opcode, 0x01);
  const Record& footer = all.back();
  EXPECT_EQ(footer.opcode, 0x02);
  Cursor f{footer.content};
  const auto summary_start = f.get<std::uint64_t>();
  const auto summary_offset_start = f.get<std::uint64_t>();
  const auto summary_crc = f.get<std::uint32_t>();
  const std::uint64_t footer_at = 8 + footer.offset;
  EXPECT_EQ(summary_crc, reference_crc(std::string_view(file).substr(
                             summary_start, footer_at + 1 + 8 + 16 - summary_start)));
  // Data end: the last record before the summary, with the CRC of everything before it.
  const auto data_end =
      std::find_if(all.begin(), all.end(), [](const Record& r) { return r.opcode == 0x0F; });
  EXPECT_NE(data_end, all.end());
  EXPECT_EQ(8 + data_end->offset + 1 + 8 + 4, summary_start);
  EXPECT_EQ(Cursor{data_end->content}.get<std::uint32_t>(),
            reference_crc(std::string_view(file).substr(0, 8 + data_end->offset)));

  // Summary offsets name every group of the summary exactly.
  const auto summary =
      records(std::string_view(file).substr(summary_start, summary_offset_start - summary_start));
  const auto offsets = records(
      std::string_view(file).substr(summary_offset_start, footer_at - summary_offset_start));
  std::uint64_t covered = 0;
  for (const auto& o : offsets) {
    EXPECT_EQ(o.opcode, 0x0E);
    Cursor c{o.content};
    const auto opcode = c.get<std::uint8_t>();
    const auto start = c.get<std::uint64_t>();
    const auto length = c.get<std::uint64_t>();
    for (const auto& r : records(std::string_view(file).substr(start, length)))
      EXPECT_EQ(r.opcode, opcode);
    covered += length;
  }
  EXPECT_EQ(covered, summary_offset_start - summary_start);

  for (const auto& r : summary) {
    Cursor c{r.content};
    if (r.opcode == 0x03) {
      const auto id = c.get<std::uint16_t>();
      const auto name = c.string();
      EXPECT_EQ(c.string(), "protobuf");
      p.schemas[id] = {std::string(name), std::string(c.string())};
    } else if (r.opcode == 0x04) {
      const auto id = c.get<std::uint16_t>();
      const auto schema = c.get<std::uint16_t>();
      const auto topic = c.string();
      EXPECT_EQ(c.string(), "protobuf");
      c.string();  // metadata
      p.channels[id] = {schema, std::string(topic)};
    } else if (r.opcode == 0x0B) {
      p.message_count = c.get<std::uint64_t>();
      EXPECT_EQ(c.get<std::uint16_t>(), p.schemas.size());
      EXPECT_EQ(c.get<std::uint32_t>(), p.channels.size());
      c.get<std::uint32_t>();  // attachments
      p.metadata_count = c.get<std::uint32_t>();
      p.chunk_count = c.get<std::uint32_t>();
      c.get<std::uint64_t>();
      c.get<std::uint64_t>();
      Cursor m{c.string()};
      while (!m.done()) {
        const auto ch = m.get<std::uint16_t>();
        p.channel_counts[ch] = m.get<std::uint64_t>();
      }
    } else if (r.opcode == 0x0D) {
      // Metadata Index -> the Metadata record in the data section, outside every chunk.
      const auto at = c.get<std::uint64_t>();
      const auto length = c.get<std::uint64_t>();
      const auto name = std::string(c.string());
      EXPECT_LT(at + length, summary_start);
      const auto record = records(std::string_view(file).substr(at, length));
      EXPECT_EQ(record.size(), 1u);
      EXPECT_EQ(record[0].opcode, 0x0C);
      Cursor m{record[0].content};
      EXPECT_EQ(m.string(), name);
      EXPECT_TRUE(p.metadata.emplace(name, parse_map(m.string())).second) << name;
      EXPECT_TRUE(m.done());
    } else if (r.opcode == 0x08) {
      const auto start_time = c.get<std::uint64_t>();
      const auto end_time = c.get<std::uint64_t>();
      const auto chunk_at = c.get<std::uint64_t>();
      const auto chunk_length = c.get<std::uint64_t>();
      std::map<std::uint16_t, std::uint64_t> index_at;
      Cursor m{c.string()};
      while (!m.done()) {
        const auto ch = m.get<std::uint16_t>();
        index_at[ch] = m.get<std::uint64_t>();
      }
      const auto index_length = c.get<std::uint64_t>();
      const auto compression = std::string(c.string());
      const auto compressed_size = c.get<std::uint64_t>();
      const auto uncompressed_size = c.get<std::uint64_t>();
      p.compressions.push_back(compression);
      const auto chunk = records(std::string_view(file).substr(chunk_at, chunk_length));
      EXPECT_EQ(chunk.size(), 1u);
      EXPECT_EQ(chunk[0].opcode, 0x06);
      Cursor k{chunk[0].content};
      EXPECT_EQ(k.get<std::uint64_t>(), start_time);
      EXPECT_EQ(k.get<std::uint64_t>(), end_time);
      EXPECT_EQ(k.get<std::uint64_t>(), uncompressed_size);
      const auto crc = k.get<std::uint32_t>();
      EXPECT_EQ(k.string(), compression);
      const auto stored = k.bytes(k.get<std::uint64_t>());
      EXPECT_EQ(stored.size(), compressed_size);
      std::string data(stored);
      if (compression == "zstd") {
        data.resize(uncompressed_size);
        EXPECT_EQ(ZSTD_decompress(data.data(), data.size(), stored.data(), stored.size()),
                  uncompressed_size);
      } else {
        EXPECT_EQ(compression, "");
      }
      EXPECT_EQ(data.size(), uncompressed_size);
      EXPECT_EQ(crc, reference_crc(data));
      // Message indexes right after the chunk, one per channel, pointing at its messages.
      const auto indexes =
          records(std::string_view(file).substr(chunk_at + chunk_length, index_length));
      EXPECT_EQ(indexes.size(), index_at.size());
      std::map<std::uint64_t, std::uint64_t> indexed;  // offset in chunk -> log time
      for (const auto& ix : indexes) {
        EXPECT_EQ(ix.opcode, 0x07);
        Cursor c2{ix.content};
        const auto ch = c2.get<std::uint16_t>();
        EXPECT_EQ(index_at.at(ch), chunk_at + chunk_length + ix.offset);
        Cursor e{c2.string()};
        while (!e.done()) {
          const auto t = e.get<std::uint64_t>();
          indexed[e.get<std::uint64_t>()] = t;
        }
      }
      std::size_t in_chunk = 0;
      for (const auto& inner : records(data)) {
        if (inner.opcode != 0x05) continue;
        Cursor mc{inner.content};
        Message msg{mc.get<std::uint16_t>(), mc.get<std::uint32_t>(), mc.get<std::uint64_t>(),
                    mc.get<std::uint64_t>(), std::string(inner.content.substr(22))};
        EXPECT_EQ(indexed.at(inner.offset), msg.log_time);
        EXPECT_GE(msg.log_time, start_time);
        EXPECT_LE(msg.log_time, end_time);
        p.messages.push_back(std::move(msg));
        ++in_chunk;
      }
      EXPECT_EQ(in_chunk, indexed.size());
    }
  }
  EXPECT_EQ(p.chunk_count, p.compressions.size());
  EXPECT_EQ(p.message_count, p.messages.size());
  EXPECT_EQ(p.metadata_count, p.metadata.size());
  return p;
}

TEST(Mcap, Crc32IsTheIeeeOne) {
  EXPECT_EQ(mcap::crc32("123456789"), 0xCBF43926U);
  EXPECT_EQ(mcap::crc32(""), 0U);
  EXPECT_EQ(mcap::crc32("6789", mcap::crc32("12345")), 0xCBF43926U);
}

TEST(Mcap, AnEmptyFileHasEverySection) {
  std::string file;
  mcap::Writer w([&](std::string_view b) { file.append(b); }, {});
  w.finish();
  const Parsed p = parse(file);
  EXPECT_EQ(p.message_count, 0u);
  EXPECT_EQ(p.chunk_count, 0u);
}

class McapWriterTest : public ::testing::TestWithParam<mcap::Compression> {};

TEST_P(McapWriterTest, ManyChunksReadBackByTheirIndex) {
  std::string file;
  mcap::WriterOptions o;
  o.compression = GetParam();
  o.chunk_bytes = 2000;
  mcap::Writer w([&](std::string_view b) { file.append(b); }, o);
  const auto s = w.add_schema("a.B", "protobuf", std::string("\x00\x01\x02", 3));
  const auto a = w.add_channel(s, "frame/left", "protobuf", {{"k", "v"}});
  const auto b = w.add_channel(s, "event", "protobuf");
  std::vector<Message> written;
  for (std::uint32_t i = 0; i < 300; ++i) {
    const std::uint16_t ch = i % 3 == 0 ? b : a;
    // Log times mostly rise; every 7th steps back, as a clock that jumped.
    const std::uint64_t t = 1'000'000'000ULL + i * 1000 - (i % 7 == 0 ? 1500 : 0);
    std::string data(i % 50, static_cast<char>('a' + i % 26));
    w.write_message(ch, i, t, t - 5, data);
    written.push_back({ch, i, t, t - 5, data});
    // Metadata between messages closes the open chunk: it is never written inside one.
    if (i == 150) w.add_metadata("middle", {{"k", "v"}, {"empty", ""}});
  }
  w.add_metadata("end", {});
  w.finish();
  EXPECT_EQ(w.bytes_written(), file.size());
  const Parsed p = parse(file);
  EXPECT_GT(p.chunk_count, 5u);
  for (const auto& c : p.compressions)
    EXPECT_EQ(c, GetParam() == mcap::Compression::kZstd ? "zstd" : "");
  ASSERT_EQ(p.messages.size(), written.size());
  for (std::size_t i = 0; i < written.size(); ++i) {
    EXPECT_EQ(p.messages[i].channel, written[i].channel);
    EXPECT_EQ(p.messages[i].sequence, written[i].sequence);
    EXPECT_EQ(p.messages[i].log_time, written[i].log_time);
    EXPECT_EQ(p.messages[i].publish_time, written[i].publish_time);
    EXPECT_EQ(p.messages[i].data, written[i].data);
  }
  EXPECT_EQ(p.channel_counts.at(a), 200u);
  EXPECT_EQ(p.channel_counts.at(b), 100u);
  EXPECT_EQ(p.channels.at(a).second, "frame/left");
  EXPECT_EQ(p.schemas.at(s).first, "a.B");
  EXPECT_EQ(p.metadata, (std::map<std::string, std::map<std::string, std::string>>{
                            {"middle", {{"k", "v"}, {"empty", ""}}}, {"end", {}}}));
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapWriterTest,
                         ::testing::Values(mcap::Compression::kNone, mcap::Compression::kZstd));

TEST(Mcap, RefusesUnknownIdsAndCompressions) {
  mcap::Writer w([](std::string_view) {}, {});
  EXPECT_THROW(w.add_channel(1, "t", "protobuf"), std::invalid_argument);
  EXPECT_THROW(w.write_message(1, 0, 0, 0, ""), std::invalid_argument);
  EXPECT_THROW(mcap::parse_compression("lz4"), std::invalid_argument);
}

// protoc's json_name, written here from its rule: the field name with each '_' dropped and the
// letter after it upper-cased ("measure_time_us" -> "measureTimeUs").
std::string lower_camel(std::string_view name) {
  std::string out;
  bool upper = false;
  for (const char ch : name) {
    if (ch == '_') {
      upper = true;
      continue;
    }
    out += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(ch))) : ch;
    upper = false;
  }
  return out;
}

// Every field of `type` and of the types nested in it has protoc's json_name; returns how many.
int expect_json_names(const google::protobuf::DescriptorProto& type, const std::string& scope) {
  int fields = 0;
  for (const auto& f : type.field()) {
    EXPECT_TRUE(f.has_json_name()) << scope << "." << f.name();
    EXPECT_EQ(f.json_name(), lower_camel(f.name())) << scope << "." << f.name();
    ++fields;
  }
  for (const auto& nested : type.nested_type())
    fields += expect_json_names(nested, scope + "." + nested.name());
  return fields;
}

// A log as the recorder writes it, exported: every message on its topic's channel, unwrapped,
// decodable from the embedded FileDescriptorSet alone (as Foxglove decodes it).
TEST(McapExport, UnwrapsEnvelopesAndEmbedsTheirSchemas) {
  TempDir dir;
  const auto log = dir / "run.tlog";
  {
    v1::LogHeader h;
    h.set_writer("mcap_test");
    h.set_created_ns(1'700'000'000'123'456'789);
    h.set_host("hand-pc");
    h.set_note("a run");
    auto* source = h.add_sources();
    source->set_endpoint("tcp://x");
    source->add_topics("frame/");
    source->add_topics("raw/");
    h.add_sources()->set_endpoint("tcp://y");
    h.mutable_sources(1)->set_curve(true);
    recording::LogWriter w(log, h, {});
    std::string buf;
    for (int i = 0; i < 30; ++i) {
      v1::Envelope env;
      env.set_schema_version(wire::kSchemaVersion);
      auto* f = env.mutable_tactile_frame();
      f->set_sensor_id("left");
      f->set_sequence(static_cast<std::uint64_t>(i));
      f->set_status(v1::FRAME_STATUS_COMPLETE);
      f->set_publish_timestamp_ns(5'000 + i);
      auto* e = f->add_elements();
      e->set_id(3);
      e->set_fz_n(0.25 * i);
      wire::encode(env, buf);
      ASSERT_EQ(w.append(1'000'000 + i * 10, "frame/left", "tcp://x", v1::PAYLOAD_KIND_ENVELOPE,
                         wire::bytes_of(buf)),
                recording::WriteStatus::kOk);
      if (i % 10 == 4) {
        v1::Envelope ev;
        ev.set_schema_version(wire::kSchemaVersion);
        ev.mutable_event()->set_kind(v1::EVENT_KIND_RECOMPRESS);
        ev.mutable_event()->set_time_ns(7'000 + i);
        ev.mutable_event()->set_text("e" + std::to_string(i));
        wire::encode(ev, buf);
        ASSERT_EQ(w.append(1'000'000 + i * 10 + 1, "event", "tcp://y", v1::PAYLOAD_KIND_ENVELOPE,
                           wire::bytes_of(buf)),
                  recording::WriteStatus::kOk);
      }
    }
    v1::RawFrame raw;
    raw.set_sensor_id("left");
    raw.set_width(2);
    raw.set_height(1);
    raw.set_pixels(std::string("\x01\x02", 2));
    ASSERT_EQ(w.append(2'000'000, "raw/left", "tcp://x", v1::PAYLOAD_KIND_RAW_FRAME,
                       wire::bytes_of(raw.SerializeAsString())),
              recording::WriteStatus::kOk);
    ASSERT_EQ(w.append(2'000'001, "frame/left", "tcp://x", v1::PAYLOAD_KIND_ENVELOPE,
                       wire::bytes_of(std::string("\xff\xff\xff", 3))),
              recording::WriteStatus::kOk);
    ASSERT_EQ(w.close(), recording::WriteStatus::kOk);
  }
  recording::LogReader in(log);
  std::string file;
  mcap::ExportOptions o;
  std::uint64_t ticks = 0;
  o.progress = [&](const recording::LogReader&, std::uint64_t records) {
    ticks = records;
    return true;
  };
  const auto result = mcap::export_log(
      in, [&](std::string_view b) { file.append(b); }, o);
  EXPECT_EQ(result.records, 35u);
  EXPECT_EQ(ticks, 35u);
  EXPECT_EQ(result.messages, 34u);
  EXPECT_EQ(result.skipped, 1u);
  EXPECT_NE(result.skip_problem.find("frame/left"), std::string::npos) << result.skip_problem;
  EXPECT_EQ(result.end, recording::ReadStatus::kEnd);
  const Parsed p = parse(file);
  std::map<std::string, std::uint16_t> by_topic;
  for (const auto& [id, ch] : p.channels)
    by_topic[ch.second] = id;
  ASSERT_EQ(by_topic.size(), 3u);
  EXPECT_EQ(p.channel_counts.at(by_topic.at("frame/left")), 30u);
  EXPECT_EQ(p.channel_counts.at(by_topic.at("event")), 3u);
  EXPECT_EQ(p.channel_counts.at(by_topic.at("raw/left")), 1u);

  // The log's header, as one Metadata record.
  EXPECT_EQ(p.metadata.size(), 1u);
  EXPECT_EQ(p.metadata.at("tactile_log_header"),
            (std::map<std::string, std::string>{{"format", "tactile-log/1"},
                                                {"created_ns", "1700000000123456789"},
                                                {"writer", "mcap_test"},
                                                {"host", "hand-pc"},
                                                {"note", "a run"},
                                                {"log_file", "run.tlog"},
                                                {"source.0.endpoint", "tcp://x"},
                                                {"source.0.topics", "frame/,raw/"},
                                                {"source.0.curve", "false"},
                                                {"source.1.endpoint", "tcp://y"},
                                                {"source.1.topics", ""},
                                                {"source.1.curve", "true"}}));

  // Every field of every message type embedded has protoc's json_name (TactileFrame's
  // measure_time_us is measureTimeUs).
  for (const auto& [id, schema] : p.schemas) {
    google::protobuf::FileDescriptorSet set;
    ASSERT_TRUE(set.ParseFromString(schema.second));
    int fields = 0;
    for (const auto& file_proto : set.file()) {
      for (const auto& type : file_proto.message_type())
        fields += expect_json_names(type, file_proto.package() + "." + type.name());
    }
    EXPECT_GT(fields, 10) << schema.first;
  }
  EXPECT_NE(p.schemas.begin()->second.second.find("measureTimeUs"), std::string::npos);

  // Decode each message with a pool built only from its schema's FileDescriptorSet.
  std::map<std::uint16_t, std::vector<std::string>> text;
  for (const auto& m : p.messages) {
    const auto& [schema_id, topic] = p.channels.at(m.channel);
    const auto& [name, data] = p.schemas.at(schema_id);
    google::protobuf::FileDescriptorSet set;
    ASSERT_TRUE(set.ParseFromString(data));
    google::protobuf::DescriptorPool pool;
    for (const auto& file_proto : set.file())
      ASSERT_NE(pool.BuildFile(file_proto), nullptr);
    const auto* type = pool.FindMessageTypeByName(name);
    ASSERT_NE(type, nullptr) << name;
    google::protobuf::DynamicMessageFactory factory(&pool);
    std::unique_ptr<google::protobuf::Message> msg(factory.GetPrototype(type)->New());
    ASSERT_TRUE(msg->ParseFromString(m.data));
    text[m.channel].push_back(msg->ShortDebugString());
    if (topic == "frame/left") {
      EXPECT_EQ(name, "tactile.v1.TactileFrame");
      EXPECT_EQ(m.publish_time, 5'000 + m.sequence);
      EXPECT_EQ(m.log_time, 1'000'000 + m.sequence * 10);
    } else if (topic == "event") {
      EXPECT_EQ(name, "tactile.v1.Event");
    } else {
      EXPECT_EQ(name, "tactile.v1.RawFrame");
      EXPECT_EQ(m.publish_time, m.log_time);  // no receive time in this raw frame: the log time
    }
  }
  EXPECT_EQ(text.at(by_topic.at("frame/left"))[7],
            "sensor_id: \"left\" sequence: 7 publish_timestamp_ns: 5007 status: "
            "FRAME_STATUS_COMPLETE elements { id: 3 fz_n: 1.75 }");
  EXPECT_EQ(text.at(by_topic.at("event"))[1],
            "time_ns: 7014 kind: EVENT_KIND_RECOMPRESS text: \"e14\"");
}

TEST(McapExport, AFileDescriptorSetHoldsTheFileAndItsImports) {
  google::protobuf::FileDescriptorSet set;
  ASSERT_TRUE(set.ParseFromString(mcap::file_descriptor_set(*v1::GroundTruth::descriptor())));
  ASSERT_EQ(set.file_size(), 1);  // tactile.proto imports nothing
  EXPECT_EQ(set.file(0).name(), "tactile/v1/tactile.proto");
  EXPECT_EQ(set.file(0).package(), "tactile.v1");
  ASSERT_TRUE(set.ParseFromString(
      mcap::file_descriptor_set(*google::protobuf::FileDescriptorSet::descriptor())));
  EXPECT_EQ(set.file(set.file_size() - 1).name(), "google/protobuf/descriptor.proto");
}

TEST(McapExport, OwnTimeIsTheMessagesTime) {
  v1::TactileFrame f;
  f.set_publish_timestamp_ns(11);
  f.set_camera_timestamp_ns(3);
  EXPECT_EQ(mcap::own_time_ns(f), 11);
  v1::GroundTruth g;
  g.set_time_ns(12);
  EXPECT_EQ(mcap::own_time_ns(g), 12);
  v1::ArmCommand c;
  c.set_send_timestamp_ns(13);
  EXPECT_EQ(mcap::own_time_ns(c), 13);
  EXPECT_EQ(mcap::own_time_ns(v1::Hold()), 0);
}

TEST(AtomicFileWriter, AppearsWholeOrNotAtAll) {
  TempDir dir;
  const auto path = dir / "out.bin";
  util::write_file_atomic(path, "old");
  {
    util::AtomicFileWriter f(path);
    f.write("new ");
    f.write("content");
    EXPECT_EQ(util::read_file(path), "old");
  }  // destroyed without commit: the old file stays, no temporary file is left
  EXPECT_EQ(util::read_file(path), "old");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);
  util::AtomicFileWriter f(path);
  f.write("new ");
  f.write("content");
  f.commit();
  EXPECT_EQ(util::read_file(path), "new content");
}

}  // namespace
}  // namespace tactile
