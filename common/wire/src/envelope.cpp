#include "tactile/wire/envelope.hpp"

// SetLogHandler: public API of protobuf 3.21 (Debian bookworm), declared in this header.
#include <google/protobuf/stubs/logging.h>

#include <atomic>
#include <chrono>

#include "tactile/util/log.hpp"
#include "tactile/util/text.hpp"

namespace tactile::wire {

namespace {

std::atomic<std::int64_t> g_last_log_ms{0};
std::atomic<std::uint64_t> g_suppressed{0};

void protobuf_log(google::protobuf::LogLevel level, const char* file, int line,
                  const std::string& message) {
  (void)file;
  (void)line;
  const std::int64_t now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                                  std::chrono::steady_clock::now().time_since_epoch())
                                  .count();
  std::int64_t last = g_last_log_ms.load();
  if (now_ms - last < 1000 || !g_last_log_ms.compare_exchange_strong(last, now_ms)) {
    ++g_suppressed;
    return;
  }
  const std::uint64_t more = g_suppressed.exchange(0);
  const std::string text = util::one_line(message);
  if (level >= google::protobuf::LOGLEVEL_ERROR) {
    util::log_error("protobuf: {}{}", text,
                    more > 0 ? " (and " + std::to_string(more) + " more)" : "");
  } else {
    util::log_warn("protobuf: {}{}", text,
                   more > 0 ? " (and " + std::to_string(more) + " more)" : "");
  }
}

}  // namespace

std::string frame_topic(std::string_view sensor_id) {
  return std::string(kFrameTopicPrefix).append(sensor_id);
}

std::string stats_topic(std::string_view sensor_id) {
  return std::string(kStatsTopicPrefix).append(sensor_id);
}

std::string raw_topic(std::string_view sensor_id) {
  return std::string(kRawTopicPrefix).append(sensor_id);
}

void install_protobuf_log_handler() {
  google::protobuf::SetLogHandler(&protobuf_log);
}

const char* to_string(DecodeStatus s) {
  switch (s) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kTooLarge:
      return "too large";
    case DecodeStatus::kMalformed:
      return "malformed";
    case DecodeStatus::kWrongVersion:
      return "wrong schema version";
    case DecodeStatus::kEmpty:
      return "empty";
    case DecodeStatus::kInvalid:
      return "invalid value";
  }
  return "unknown";
}

DecodeStatus decode(std::span<const std::uint8_t> bytes, v1::Envelope& out) noexcept {
  if (bytes.size() > kMaxMessageBytes) return DecodeStatus::kTooLarge;
  try {
    if (!out.ParseFromArray(bytes.data(), static_cast<int>(bytes.size())))
      return DecodeStatus::kMalformed;
  } catch (...) {
    return DecodeStatus::kMalformed;  // allocation failure inside the parser
  }
  if (out.schema_version() != kSchemaVersion) return DecodeStatus::kWrongVersion;
  if (out.body_case() == v1::Envelope::BODY_NOT_SET) return DecodeStatus::kEmpty;
  return DecodeStatus::kOk;
}

namespace {

google::protobuf::ArenaOptions arena_options(std::vector<char>& block) {
  google::protobuf::ArenaOptions o;
  o.initial_block = block.data();
  o.initial_block_size = block.size();
  return o;
}

}  // namespace

EnvelopeDecoder::EnvelopeDecoder(std::size_t block_bytes)
    : block_(block_bytes), arena_(arena_options(block_)) {
  envelope_ = google::protobuf::Arena::CreateMessage<v1::Envelope>(&arena_);
}

DecodeStatus EnvelopeDecoder::decode(std::span<const std::uint8_t> bytes) noexcept {
  arena_.Reset();
  envelope_ = google::protobuf::Arena::CreateMessage<v1::Envelope>(&arena_);
  return wire::decode(bytes, *envelope_);
}

void encode(v1::Envelope& envelope, std::string& buffer) {
  envelope.set_schema_version(kSchemaVersion);
  buffer.clear();
  envelope.SerializeToString(&buffer);
}

}  // namespace tactile::wire
