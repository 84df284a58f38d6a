// libFuzzer target: wire::read_arm_command (what an arm controller does with every ArmCommand).
// Promises: never throws or crashes; an accepted command keeps the rules of wire_checks.hpp.
#include <cstddef>
#include <cstdint>

#include "wire_checks.hpp"

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  tactile::fuzz::silence_protobuf_log();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tactile;
  static v1::ArmCommand in;
  static wire::ReceivedCommand out;
  if (!in.ParseFromArray(data, static_cast<int>(size))) return 0;
  const wire::DecodeStatus status = wire::read_arm_command(in, fuzz::kFingertipIds, out);
  fuzz::check_arm_command(in, status, out);
  return 0;
}
