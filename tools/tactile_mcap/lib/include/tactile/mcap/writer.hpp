#pragma once

// A writer of MCAP files (https://mcap.dev/spec, major version 0): the records written by hand,
// so that a recording opens in Foxglove and PlotJuggler without an MCAP library.
//
// The file it writes: magic, Header, then Metadata records and chunks (Schema, Channel and Message
// records, zstd or uncompressed) each followed by a Message Index per channel, Data End with the
// data section's CRC, a summary section (every Schema, every Channel, one Statistics, a Metadata
// Index per Metadata record, a Chunk Index per chunk, grouped by opcode), a Summary Offset per
// group, the Footer with the summary's CRC, magic. A reader can therefore open it by its index
// (footer -> summary -> chunk) or read it front to back.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tactile::mcap {

enum class Compression : std::uint8_t { kNone, kZstd };

// Parses "none" or "zstd"; throws std::invalid_argument naming the value otherwise.
Compression parse_compression(std::string_view text);

struct WriterOptions {
  Compression compression = Compression::kZstd;
  int zstd_level = 3;
  // A chunk is closed once its uncompressed records reach this size.
  std::size_t chunk_bytes = 1 << 20;
  std::string profile;  // the Header's profile; "" for none of the well-known ones
  std::string library;  // the Header's library, e.g. "tactile_mcap 0.1.0"
};

// CRC-32 (IEEE 802.3, the one MCAP uses) of `bytes`, continued from `crc` (0 to start).
std::uint32_t crc32(std::string_view bytes, std::uint32_t crc = 0);

class Writer {
 public:
  // Receives the file's bytes in order; may throw (the writer is then unusable).
  using Sink = std::function<void(std::string_view)>;

  // Writes the magic and the Header.
  Writer(Sink sink, WriterOptions options);
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // A schema (ids from 1). For protobuf: encoding "protobuf", name the message's full name, data
  // a serialized google.protobuf.FileDescriptorSet.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  // A channel (ids from 1) on a schema of add_schema().
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding,
                            const std::map<std::string, std::string>& metadata = {});
  // One message on a channel; times in ns (publish_time: the log time when there is no other).
  void write_message(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time,
                     std::uint64_t publish_time, std::string_view data);
  // A Metadata record (name and key/value pairs), written between chunks: the open chunk is
  // closed first. Indexed in the summary by a Metadata Index.
  void add_metadata(std::string_view name, const std::map<std::string, std::string>& metadata);
  // Closes the last chunk and writes the data end, the summary, the footer and the magic.
  void finish();

  std::uint64_t bytes_written() const { return offset_; }
  std::uint64_t messages() const { return message_count_; }
  std::uint32_t chunks() const { return chunk_count_; }

 private:
  void emit(std::string_view bytes);
  void emit_record(std::uint8_t opcode, std::string_view content);
  void append_to_chunk(std::uint8_t opcode, std::string_view content);
  void close_chunk();

  Sink sink_;
  WriterOptions options_;
  std::uint64_t offset_ = 0;
  std::uint32_t crc_ = 0;  // running CRC of the section being written (data, then summary)
  bool finished_ = false;

  std::vector<std::string> schemas_;   // Schema record contents, by id - 1
  std::vector<std::string> channels_;  // Channel record contents, by id - 1
  std::vector<std::string> chunk_indexes_;
  std::vector<std::string> metadata_indexes_;

  // The open chunk.
  std::string chunk_;
  std::uint64_t chunk_start_time_ = 0;
  std::uint64_t chunk_end_time_ = 0;
  bool chunk_has_messages_ = false;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_messages_;
  std::string compressed_;
  std::string record_;

  // Statistics.
  std::uint64_t message_count_ = 0;
  std::uint32_t chunk_count_ = 0;
  std::uint64_t start_time_ = 0;
  std::uint64_t end_time_ = 0;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
};

}  // namespace tactile::mcap
