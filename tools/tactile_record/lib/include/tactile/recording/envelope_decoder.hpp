#pragma once

// Decodes Envelopes without allocating per message. wire::decode parses into a reused Envelope,
// but Protobuf's parse first clears the message, which deletes the oneof body (a TactileFrame and
// its 41 ElementReadings: about 50 allocations per frame). Here every message is parsed into a
// fresh Envelope on an arena whose first block is allocated once and reset before each message.
#include <google/protobuf/arena.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/envelope.hpp"

namespace tactile::recording {

class EnvelopeDecoder {
 public:
  // `block_bytes`: large enough for the largest message decoded (a TactileFrame of 41 elements
  // takes about 8 KiB on the arena); larger ones still decode, with allocations.
  explicit EnvelopeDecoder(std::size_t block_bytes = 256 << 10);
  EnvelopeDecoder(const EnvelopeDecoder&) = delete;
  EnvelopeDecoder& operator=(const EnvelopeDecoder&) = delete;

  // The rules of wire::decode. The envelope is valid until the next call.
  wire::DecodeStatus decode(std::span<const std::uint8_t> bytes) noexcept;
  const v1::Envelope& envelope() const { return *envelope_; }

 private:
  std::vector<char> block_;
  google::protobuf::Arena arena_;
  v1::Envelope* envelope_ = nullptr;
};

}  // namespace tactile::recording
