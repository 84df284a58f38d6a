#pragma once

// A tactile log (docs/recording.md) as an MCAP file that Foxglove and PlotJuggler open: one
// channel per topic (and message type), the Envelope unwrapped so that each message is the
// TactileFrame, SensorStats, Event, Decision, GroundTruth, ArmCommand, ArmState or Heartbeat it
// carries, raw camera frames as tactile.v1.RawFrame; every schema embedded as a FileDescriptorSet
// (schema encoding "protobuf", message encoding "protobuf") with every field's json_name, as protoc
// writes it; the log's header as a Metadata record. log_time is the record's receive time,
// publish_time the message's own time where it has one (docs/recording.md#mcap-export).
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "tactile/mcap/writer.hpp"
#include "tactile/recording/log_reader.hpp"
#include "tactile/v1/log.pb.h"

namespace tactile::mcap {

// A serialized google.protobuf.FileDescriptorSet of the file that defines `message` and every
// file it imports, dependencies first: what an MCAP "protobuf" schema holds. Every field carries
// its json_name (lowerCamelCase of its name), as in the sets protoc writes: readers that name
// fields by it (JSON, protobuf-es) then name them as for protoc's descriptors.
std::string file_descriptor_set(const google::protobuf::Descriptor& message);

// The name of the Metadata record that holds the log's header.
inline constexpr const char* kLogHeaderMetadata = "tactile_log_header";

// The log's header (docs/recording.md, LogHeader) as the Metadata record's pairs: format,
// created_ns, writer, host, note, the log file's name (log_file), and per source i (from 0)
// source.i.endpoint, source.i.topics (comma-separated prefixes; "" for every topic) and
// source.i.curve ("true"/"false").
std::map<std::string, std::string> log_header_metadata(const v1::LogHeader& header,
                                                       const std::string& log_file);

// The message's own time in ns (publish_timestamp_ns of a TactileFrame, time_ns of an Event...),
// or 0 when it has none.
std::int64_t own_time_ns(const google::protobuf::Message& message);

struct ExportOptions {
  WriterOptions writer;
  // Called after every record with the reader (for position() and file_size()) and the records
  // read; returns false to stop the export (a stop request).
  std::function<bool(const recording::LogReader&, std::uint64_t records)> progress;
};

struct ExportResult {
  std::uint64_t records = 0;   // records read after the header
  std::uint64_t messages = 0;  // messages written
  std::uint64_t skipped = 0;   // records whose payload does not decode (see problem)
  std::map<std::string, std::uint64_t> per_topic;  // messages written per topic
  recording::ReadStatus end = recording::ReadStatus::kEnd;
  std::string skip_problem;  // the first skipped record: topic and why
  bool stopped = false;      // progress() asked to stop; the file is then not finished
  std::uint32_t chunks = 0;
};

// Reads every record of `in` and writes the MCAP file to `sink`. The file is finished (summary,
// footer) unless progress() stopped the export. Throws std::runtime_error on a sink failure.
ExportResult export_log(recording::LogReader& in, const Writer::Sink& sink,
                        const ExportOptions& options);

}  // namespace tactile::mcap
