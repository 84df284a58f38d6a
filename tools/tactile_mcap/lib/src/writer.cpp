#include "tactile/mcap/writer.hpp"

#include <zstd.h>

#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>

namespace tactile::mcap {
namespace {

constexpr std::string_view kMagic{"\x89MCAP0\r\n", 8};

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Little-endian serialisation of the spec's types.
template <typename T>
void put(std::string& out, T value) {
  for (std::size_t i = 0; i < sizeof(T); ++i)
    out.push_back(static_cast<char>((static_cast<std::uint64_t>(value) >> (8 * i)) & 0xFF));
}
void put_string(std::string& out, std::string_view s) {
  put<std::uint32_t>(out, static_cast<std::uint32_t>(s.size()));
  out.append(s);
}
// Map<string, string>: the pairs' byte length, then key and value of each pair.
void put_map(std::string& out, const std::map<std::string, std::string>& map) {
  std::string pairs;
  for (const auto& [k, v] : map) {
    put_string(pairs, k);
    put_string(pairs, v);
  }
  put_string(out, pairs);
}

constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k)
      c = (c & 1) ? 0xEDB88320U ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr auto kCrcTable = make_crc_table();

}  // namespace

Compression parse_compression(std::string_view text) {
  if (text == "none") return Compression::kNone;
  if (text == "zstd") return Compression::kZstd;
  throw std::invalid_argument("compression must be none or zstd, is '" + std::string(text) + "'");
}

std::uint32_t crc32(std::string_view bytes, std::uint32_t crc) {
  crc = ~crc;
  for (const char ch : bytes)
    crc = kCrcTable[(crc ^ static_cast<std::uint8_t>(ch)) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

Writer::Writer(Sink sink, WriterOptions options)
    : sink_(std::move(sink)), options_(std::move(options)) {
  if (options_.chunk_bytes == 0) throw std::invalid_argument("chunk size must be positive");
  emit(kMagic);
  std::string header;
  put_string(header, options_.profile);
  put_string(header, options_.library);
  emit_record(kHeader, header);
}

void Writer::emit(std::string_view bytes) {
  sink_(bytes);
  offset_ += bytes.size();
  crc_ = crc32(bytes, crc_);
}

void Writer::emit_record(std::uint8_t opcode, std::string_view content) {
  record_.clear();
  record_.push_back(static_cast<char>(opcode));
  put<std::uint64_t>(record_, content.size());
  emit(record_);
  emit(content);
}

void Writer::append_to_chunk(std::uint8_t opcode, std::string_view content) {
  chunk_.push_back(static_cast<char>(opcode));
  put<std::uint64_t>(chunk_, content.size());
  chunk_.append(content);
}

std::uint16_t Writer::add_schema(std::string_view name, std::string_view encoding,
                                 std::string_view data) {
  if (finished_) throw std::logic_error("MCAP writer: add_schema after finish");
  if (schemas_.size() >= std::numeric_limits<std::uint16_t>::max())
    throw std::length_error("MCAP writer: too many schemas");
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  std::string s;
  put<std::uint16_t>(s, id);
  put_string(s, name);
  put_string(s, encoding);
  put_string(s, data);  // uint32 length-prefixed bytes, as a string
  append_to_chunk(kSchema, s);
  schemas_.push_back(std::move(s));
  return id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, std::string_view topic,
                                  std::string_view message_encoding,
                                  const std::map<std::string, std::string>& metadata) {
  if (finished_) throw std::logic_error("MCAP writer: add_channel after finish");
  if (schema_id == 0 || schema_id > schemas_.size())
    throw std::invalid_argument("MCAP writer: unknown schema id " + std::to_string(schema_id));
  if (channels_.size() >= std::numeric_limits<std::uint16_t>::max())
    throw std::length_error("MCAP writer: too many channels");
  const auto id = static_cast<std::uint16_t>(channels_.size() + 1);
  std::string c;
  put<std::uint16_t>(c, id);
  put<std::uint16_t>(c, schema_id);
  put_string(c, topic);
  put_string(c, message_encoding);
  put_map(c, metadata);
  append_to_chunk(kChannel, c);
  channels_.push_back(std::move(c));
  channel_counts_[id] = 0;
  return id;
}

void Writer::add_metadata(std::string_view name,
                          const std::map<std::string, std::string>& metadata) {
  if (finished_) throw std::logic_error("MCAP writer: add_metadata after finish");
  close_chunk();
  std::string m;
  put_string(m, name);
  put_map(m, metadata);
  const std::uint64_t at = offset_;
  emit_record(kMetadata, m);
  std::string index;
  put<std::uint64_t>(index, at);
  put<std::uint64_t>(index, offset_ - at);
  put_string(index, name);
  metadata_indexes_.push_back(std::move(index));
}

void Writer::write_message(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time,
                           std::uint64_t publish_time, std::string_view data) {
  if (finished_) throw std::logic_error("MCAP writer: write_message after finish");
  if (channel_id == 0 || channel_id > channels_.size())
    throw std::invalid_argument("MCAP writer: unknown channel id " + std::to_string(channel_id));
  chunk_messages_[channel_id].emplace_back(log_time, chunk_.size());
  chunk_.push_back(static_cast<char>(kMessage));
  put<std::uint64_t>(chunk_, 2 + 4 + 8 + 8 + data.size());
  put<std::uint16_t>(chunk_, channel_id);
  put<std::uint32_t>(chunk_, sequence);
  put<std::uint64_t>(chunk_, log_time);
  put<std::uint64_t>(chunk_, publish_time);
  chunk_.append(data);
  if (!chunk_has_messages_ || log_time < chunk_start_time_) chunk_start_time_ = log_time;
  if (!chunk_has_messages_ || log_time > chunk_end_time_) chunk_end_time_ = log_time;
  if (message_count_ == 0 || log_time < start_time_) start_time_ = log_time;
  if (message_count_ == 0 || log_time > end_time_) end_time_ = log_time;
  chunk_has_messages_ = true;
  ++message_count_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= options_.chunk_bytes) close_chunk();
}

void Writer::close_chunk() {
  if (chunk_.empty()) return;
  std::string_view records = chunk_;
  std::string_view compression;
  if (options_.compression == Compression::kZstd) {
    compressed_.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n = ZSTD_compress(compressed_.data(), compressed_.size(), chunk_.data(),
                                        chunk_.size(), options_.zstd_level);
    if (ZSTD_isError(n) != 0)
      throw std::runtime_error(std::string("MCAP writer: zstd: ") + ZSTD_getErrorName(n));
    compressed_.resize(n);
    records = compressed_;
    compression = "zstd";
  }
  const std::uint64_t start = chunk_has_messages_ ? chunk_start_time_ : 0;
  const std::uint64_t end = chunk_has_messages_ ? chunk_end_time_ : 0;
  std::string head;
  put<std::uint64_t>(head, start);
  put<std::uint64_t>(head, end);
  put<std::uint64_t>(head, chunk_.size());
  put<std::uint32_t>(head, crc32(chunk_));
  put_string(head, compression);
  put<std::uint64_t>(head, records.size());
  const std::uint64_t chunk_start = offset_;
  record_.clear();
  record_.push_back(static_cast<char>(kChunk));
  put<std::uint64_t>(record_, head.size() + records.size());
  record_.append(head);
  emit(record_);
  emit(records);
  const std::uint64_t chunk_length = offset_ - chunk_start;

  // One Message Index per channel with messages in the chunk, entries in log time order.
  std::string offsets;
  const std::uint64_t index_start = offset_;
  for (auto& [channel, entries] : chunk_messages_) {
    std::stable_sort(entries.begin(), entries.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    put<std::uint16_t>(offsets, channel);
    put<std::uint64_t>(offsets, offset_);
    std::string index;
    put<std::uint16_t>(index, channel);
    put<std::uint32_t>(index, static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, at] : entries) {
      put<std::uint64_t>(index, time);
      put<std::uint64_t>(index, at);
    }
    emit_record(kMessageIndex, index);
  }
  std::string ci;
  put<std::uint64_t>(ci, start);
  put<std::uint64_t>(ci, end);
  put<std::uint64_t>(ci, chunk_start);
  put<std::uint64_t>(ci, chunk_length);
  put_string(ci, offsets);
  put<std::uint64_t>(ci, offset_ - index_start);
  put_string(ci, compression);
  put<std::uint64_t>(ci, records.size());
  put<std::uint64_t>(ci, chunk_.size());
  chunk_indexes_.push_back(std::move(ci));
  ++chunk_count_;

  chunk_.clear();
  chunk_messages_.clear();
  chunk_has_messages_ = false;
}

void Writer::finish() {
  if (finished_) return;
  close_chunk();
  finished_ = true;
  std::string data_end;
  put<std::uint32_t>(data_end, crc_);  // every byte from the file's start to here
  emit_record(kDataEnd, data_end);

  const std::uint64_t summary_start = offset_;
  crc_ = 0;
  struct Group {
    std::uint8_t opcode;
    std::uint64_t start;
    std::uint64_t length;
  };
  std::vector<Group> groups;
  const auto group = [&](std::uint8_t opcode, const std::vector<std::string>& records) {
    if (records.empty()) return;
    const std::uint64_t start = offset_;
    for (const auto& r : records)
      emit_record(opcode, r);
    groups.push_back({opcode, start, offset_ - start});
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  std::string stats;
  put<std::uint64_t>(stats, message_count_);
  put<std::uint16_t>(stats, static_cast<std::uint16_t>(schemas_.size()));
  put<std::uint32_t>(stats, static_cast<std::uint32_t>(channels_.size()));
  put<std::uint32_t>(stats, 0);  // attachments
  put<std::uint32_t>(stats, static_cast<std::uint32_t>(metadata_indexes_.size()));
  put<std::uint32_t>(stats, chunk_count_);
  put<std::uint64_t>(stats, message_count_ > 0 ? start_time_ : 0);
  put<std::uint64_t>(stats, message_count_ > 0 ? end_time_ : 0);
  std::string counts;
  for (const auto& [channel, n] : channel_counts_) {
    put<std::uint16_t>(counts, channel);
    put<std::uint64_t>(counts, n);
  }
  put_string(stats, counts);
  group(kStatistics, {stats});
  group(kMetadataIndex, metadata_indexes_);
  group(kChunkIndex, chunk_indexes_);

  const std::uint64_t summary_offset_start = offset_;
  for (const auto& g : groups) {
    std::string so;
    put<std::uint8_t>(so, g.opcode);
    put<std::uint64_t>(so, g.start);
    put<std::uint64_t>(so, g.length);
    emit_record(kSummaryOffset, so);
  }
  // The footer's CRC covers the summary, the summary offsets and the footer up to this field.
  record_.clear();
  record_.push_back(static_cast<char>(kFooter));
  put<std::uint64_t>(record_, 8 + 8 + 4);
  put<std::uint64_t>(record_, summary_start);
  put<std::uint64_t>(record_, summary_offset_start);
  put<std::uint32_t>(record_, crc32(record_, crc_));
  emit(record_);
  emit(kMagic);
}

}  // namespace tactile::mcap
