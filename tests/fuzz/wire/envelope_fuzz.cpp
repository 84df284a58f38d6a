// libFuzzer target: wire::decode (every message on every socket is an Envelope), then, as the
// programs do, the reader of whichever body it holds. Promises: never throws or crashes; an
// accepted envelope re-encodes to one that decodes the same; the readers keep theirs
// (wire_checks.hpp).
#include <cstddef>
#include <cstdint>
#include <string>

#include "wire_checks.hpp"

namespace {

using namespace tactile;

void check_round_trip(v1::Envelope& env) {
  static std::string bytes;
  static v1::Envelope again;
  wire::encode(env, bytes);
  fuzz::require(wire::decode(wire::bytes_of(bytes), again) == wire::DecodeStatus::kOk,
                "an accepted envelope, encoded again, does not decode");
  fuzz::require(again.body_case() == env.body_case(), "the body changed on a round trip");
  std::string twice;
  wire::encode(again, twice);
  fuzz::require(twice == bytes, "encoding is not stable across a round trip");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  tactile::fuzz::silence_protobuf_log();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Calibration cal = fuzz::wire_calibration();
  // Reused across inputs, as the programs reuse theirs.
  static v1::Envelope env;
  static wire::ReceivedFrame frame;
  static wire::ReceivedCommand command;
  static wire::ArmStateData state;
  const wire::DecodeStatus status = wire::decode({data, size}, env);
  if (size > wire::kMaxMessageBytes) {
    fuzz::require(status == wire::DecodeStatus::kTooLarge, "an oversized message was parsed");
  }
  if (status != wire::DecodeStatus::kOk) return 0;
  fuzz::require(env.schema_version() == wire::kSchemaVersion, "accepted another schema version");
  fuzz::require(env.body_case() != v1::Envelope::BODY_NOT_SET, "accepted an envelope with no body");
  if (env.has_tactile_frame()) {
    const auto s = wire::read_tactile_frame(env.tactile_frame(), cal, frame);
    fuzz::check_tactile_frame(env.tactile_frame(), cal, s, frame);
  } else if (env.has_arm_command()) {
    const auto s = wire::read_arm_command(env.arm_command(), fuzz::kFingertipIds, command);
    fuzz::check_arm_command(env.arm_command(), s, command);
  } else if (env.has_arm_state()) {
    const auto s = wire::read_arm_state(env.arm_state(), fuzz::kFingertipIds, state);
    fuzz::check_arm_state(s, state);
  }
  check_round_trip(env);
  return 0;
}
