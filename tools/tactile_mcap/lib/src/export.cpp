#include "tactile/mcap/export.hpp"

#include <google/protobuf/descriptor.pb.h>

#include <set>
#include <utility>
#include <vector>

#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/envelope.hpp"

namespace tactile::mcap {
namespace {

namespace gp = google::protobuf;

void add_file(const gp::FileDescriptor& file, std::set<std::string>& seen,
              gp::FileDescriptorSet& set) {
  if (!seen.insert(file.name()).second) return;
  for (int i = 0; i < file.dependency_count(); ++i)
    add_file(*file.dependency(i), seen, set);
  gp::FileDescriptorProto* proto = set.add_file();
  file.CopyTo(proto);
  // CopyTo leaves json_name out; protoc's descriptor sets (and Foxglove's own) carry it.
  file.CopyJsonNameTo(proto);
}

std::uint64_t unsigned_time(std::int64_t ns) {
  return ns > 0 ? static_cast<std::uint64_t>(ns) : 0;
}

}  // namespace

std::string file_descriptor_set(const gp::Descriptor& message) {
  gp::FileDescriptorSet set;
  std::set<std::string> seen;
  add_file(*message.file(), seen, set);
  return set.SerializeAsString();
}

std::map<std::string, std::string> log_header_metadata(const v1::LogHeader& header,
                                                       const std::string& log_file) {
  std::map<std::string, std::string> m{
      {"format", header.format()}, {"created_ns", std::to_string(header.created_ns())},
      {"writer", header.writer()}, {"host", header.host()},
      {"note", header.note()},     {"log_file", log_file}};
  for (int i = 0; i < header.sources_size(); ++i) {
    const v1::LogSource& source = header.sources(i);
    const std::string key = "source." + std::to_string(i) + ".";
    std::string topics;
    for (const std::string& t : source.topics())
      topics += (topics.empty() ? "" : ",") + t;
    m[key + "endpoint"] = source.endpoint();
    m[key + "topics"] = topics;
    m[key + "curve"] = source.curve() ? "true" : "false";
  }
  return m;
}

std::int64_t own_time_ns(const gp::Message& message) {
  if (const auto* m = dynamic_cast<const v1::TactileFrame*>(&message))
    return m->publish_timestamp_ns();
  if (const auto* m = dynamic_cast<const v1::ArmCommand*>(&message)) return m->send_timestamp_ns();
  if (const auto* m = dynamic_cast<const v1::RawFrame*>(&message)) return m->receive_timestamp_ns();
  // SensorStats, ArmState, Heartbeat, Event, GroundTruth: time_ns.
  const gp::FieldDescriptor* f = message.GetDescriptor()->FindFieldByName("time_ns");
  if (f != nullptr && f->cpp_type() == gp::FieldDescriptor::CPPTYPE_INT64)
    return message.GetReflection()->GetInt64(message, f);
  return 0;
}

ExportResult export_log(recording::LogReader& in, const Writer::Sink& sink,
                        const ExportOptions& options) {
  Writer writer(sink, options.writer);
  writer.add_metadata(kLogHeaderMetadata,
                      log_header_metadata(in.header(), in.path().filename().string()));
  ExportResult result;
  std::map<const gp::Descriptor*, std::uint16_t> schemas;
  std::map<std::pair<std::string, const gp::Descriptor*>, std::uint16_t> channels;
  std::map<std::uint16_t, std::uint32_t> sequences;
  v1::LogRecord rec;
  v1::Envelope envelope;
  v1::RawFrame raw;
  std::string data;
  const gp::OneofDescriptor* body = v1::Envelope::descriptor()->FindOneofByName("body");

  const auto skip = [&](const std::string& why) {
    if (result.skipped++ == 0) result.skip_problem = "topic '" + rec.topic() + "': " + why;
  };
  while ((result.end = in.next(rec)) == recording::ReadStatus::kRecord) {
    ++result.records;
    const gp::Message* message = nullptr;
    if (rec.kind() == v1::PAYLOAD_KIND_RAW_FRAME) {
      if (raw.ParseFromString(rec.payload())) {
        message = &raw;
      } else {
        skip("not a RawFrame");
      }
    } else {
      const auto status = wire::decode(wire::bytes_of(rec.payload()), envelope);
      if (status == wire::DecodeStatus::kOk) {
        const gp::FieldDescriptor* f =
            envelope.GetReflection()->GetOneofFieldDescriptor(envelope, body);
        message = &envelope.GetReflection()->GetMessage(envelope, f);
      } else {
        skip(std::string("Envelope ") + wire::to_string(status));
      }
    }
    if (message != nullptr) {
      const gp::Descriptor* type = message->GetDescriptor();
      auto schema = schemas.find(type);
      if (schema == schemas.end())
        schema = schemas
                     .emplace(type, writer.add_schema(type->full_name(), "protobuf",
                                                      file_descriptor_set(*type)))
                     .first;
      auto channel = channels.find({rec.topic(), type});
      if (channel == channels.end())
        channel = channels
                      .emplace(std::make_pair(rec.topic(), type),
                               writer.add_channel(schema->second, rec.topic(), "protobuf"))
                      .first;
      data.clear();
      message->SerializeToString(&data);
      const std::uint64_t log_time = unsigned_time(rec.receive_time_ns());
      const std::int64_t own = own_time_ns(*message);
      writer.write_message(channel->second, sequences[channel->second]++, log_time,
                           own > 0 ? static_cast<std::uint64_t>(own) : log_time, data);
      ++result.messages;
      ++result.per_topic[rec.topic()];
    }
    if (options.progress && !options.progress(in, result.records)) {
      result.stopped = true;
      return result;
    }
  }
  writer.finish();
  result.chunks = writer.chunks();
  return result;
}

}  // namespace tactile::mcap
