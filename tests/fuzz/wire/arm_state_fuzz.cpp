// libFuzzer target: wire::read_arm_state (what hand_node does with every ArmState). Promises:
// never throws or crashes; an accepted state is finite, and so is the controller's feedback.
#include <cstddef>
#include <cstdint>

#include "wire_checks.hpp"

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  tactile::fuzz::silence_protobuf_log();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tactile;
  static v1::ArmState in;
  static wire::ArmStateData out;
  if (!in.ParseFromArray(data, static_cast<int>(size))) return 0;
  fuzz::check_arm_state(wire::read_arm_state(in, fuzz::kFingertipIds, out), out);
  return 0;
}
