#pragma once

// Encoding and decoding of the one message type that crosses every socket: tactile.v1.Envelope.
#include <google/protobuf/arena.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "tactile/v1/tactile.pb.h"

namespace tactile::wire {

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
