#pragma once

// The wire contract: the topics every PUB socket sends on, the one message type that crosses
// every socket (tactile.v1.Envelope) with its encoding and decoding, and the byte view the
// sockets take.
#include <google/protobuf/arena.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/v1/tactile.pb.h"

namespace tactile::wire {

// Topics: the first part of every [topic, payload] message a Publisher sends. A Subscriber
// subscribes by prefix, so a prefix below receives every sensor's messages of its kind.
// sensor_node, one TactileFrame Envelope per camera frame: "frame/<sensor_id>".
inline constexpr const char* kFrameTopicPrefix = "frame/";
// sensor_node, a SensorStats Envelope now and then: "stats/<sensor_id>".
inline constexpr const char* kStatsTopicPrefix = "stats/";
// sensor_node with raw frames on, a tactile.v1.RawFrame (not an Envelope; raw_frame.hpp):
// "raw/<sensor_id>".
inline constexpr const char* kRawTopicPrefix = "raw/";
// hand_node's events endpoint: an Event Envelope per controller event,
inline constexpr const char* kEventTopic = "event";
// a copy of every ArmCommand Envelope it sends the arm,
inline constexpr const char* kCommandTopic = "command";
// and every ArmState Envelope it receives from the arm (the arm link is point to point).
inline constexpr const char* kArmTopic = "arm";
// and a Decision Envelope per controller step run on fresh frames (what it decided on each).
inline constexpr const char* kDecisionTopic = "decision";
// The rig, a GroundTruth Envelope per rendered frame.
inline constexpr const char* kTruthTopic = "truth";

std::string frame_topic(std::string_view sensor_id);
std::string stats_topic(std::string_view sensor_id);
std::string raw_topic(std::string_view sensor_id);

// The bytes of an encoded message (encode()'s buffer, a log record's payload) as the sockets,
// the decoders and the log writer take them: a view, valid while `s` is.
inline std::span<const std::uint8_t> bytes_of(std::string_view s) noexcept {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

inline constexpr std::uint32_t kSchemaVersion = 1;
// Larger messages are refused before parsing (a TactileFrame of 41 elements is about 4 KiB).
inline constexpr std::size_t kMaxMessageBytes = 1 << 20;

enum class DecodeStatus : std::uint8_t {
  kOk,
  kTooLarge,      // more than kMaxMessageBytes
  kMalformed,     // not a Protobuf Envelope
  kWrongVersion,  // schema_version other than kSchemaVersion
  kEmpty,         // no body
  kInvalid,       // parses, but a value breaks a rule (non-finite number, wrong element count...)
};
const char* to_string(DecodeStatus s);

// Parses `bytes` into `out`. Never throws. Protobuf clears `out` first, which frees its body (a
// TactileFrame of 41 elements: about 50 allocations per message): per-message paths use
// EnvelopeDecoder instead.
DecodeStatus decode(std::span<const std::uint8_t> bytes, v1::Envelope& out) noexcept;

// Decodes Envelopes without allocating per message: each is parsed into a fresh Envelope on an
// arena whose first block is allocated once and reset before every message.
class EnvelopeDecoder {
 public:
  // `block_bytes`: large enough for the largest message decoded (a TactileFrame of 41 elements
  // takes about 8 KiB on the arena); larger ones still decode, with allocations.
  explicit EnvelopeDecoder(std::size_t block_bytes = 256 << 10);
  EnvelopeDecoder(const EnvelopeDecoder&) = delete;
  EnvelopeDecoder& operator=(const EnvelopeDecoder&) = delete;

  // The rules of decode(). The envelope is valid until the next call.
  DecodeStatus decode(std::span<const std::uint8_t> bytes) noexcept;
  const v1::Envelope& envelope() const { return *envelope_; }

 private:
  std::vector<char> block_;
  google::protobuf::Arena arena_;
  v1::Envelope* envelope_ = nullptr;
};

// Routes Protobuf's own log lines (one per non-UTF-8 string it parses, for instance) to the
// program's log, at most one line a second with a count of the rest: a bad peer cannot flood
// the log. Call once at start-up.
void install_protobuf_log_handler();

// Sets the schema version and serialises into `buffer` (its capacity is reused).
void encode(v1::Envelope& envelope, std::string& buffer);

}  // namespace tactile::wire
