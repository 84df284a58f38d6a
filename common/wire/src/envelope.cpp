#include "tactile/wire/envelope.hpp"

namespace tactile::wire {

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

void encode(v1::Envelope& envelope, std::string& buffer) {
  envelope.set_schema_version(kSchemaVersion);
  buffer.clear();
  envelope.SerializeToString(&buffer);
}

}  // namespace tactile::wire
