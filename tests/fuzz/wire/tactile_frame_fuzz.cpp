// libFuzzer target: wire::read_tactile_frame against a fixed calibration (what hand_node does
// with every TactileFrame). Promises: never throws or crashes; an accepted frame keeps the rules
// of wire_checks.hpp; reading into a reused frame gives the same result as into a fresh one.
#include <cstddef>
#include <cstdint>

#include "wire_checks.hpp"

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  tactile::fuzz::silence_protobuf_log();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tactile;
  static const Calibration cal = fuzz::wire_calibration();
  static wire::ReceivedFrame reused;  // sized to the calibration once, then reused
  static v1::TactileFrame in;
  if (!in.ParseFromArray(data, static_cast<int>(size))) return 0;
  const wire::DecodeStatus status = wire::read_tactile_frame(in, cal, reused);
  fuzz::check_tactile_frame(in, cal, status, reused);
  wire::ReceivedFrame fresh;
  fuzz::require(wire::read_tactile_frame(in, cal, fresh) == status,
                "a reused frame and a fresh one read differently");
  return 0;
}
