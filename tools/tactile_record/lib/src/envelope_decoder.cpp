#include "tactile/recording/envelope_decoder.hpp"

namespace tactile::recording {
namespace {

google::protobuf::ArenaOptions options_for(std::vector<char>& block) {
  google::protobuf::ArenaOptions o;
  o.initial_block = block.data();
  o.initial_block_size = block.size();
  return o;
}

}  // namespace

EnvelopeDecoder::EnvelopeDecoder(std::size_t block_bytes)
    : block_(block_bytes), arena_(options_for(block_)) {
  envelope_ = google::protobuf::Arena::CreateMessage<v1::Envelope>(&arena_);
}

wire::DecodeStatus EnvelopeDecoder::decode(std::span<const std::uint8_t> bytes) noexcept {
  arena_.Reset();
  envelope_ = google::protobuf::Arena::CreateMessage<v1::Envelope>(&arena_);
  return wire::decode(bytes, *envelope_);
}

}  // namespace tactile::recording
