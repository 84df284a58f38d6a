#pragma once

// How often one log message may be written: at most once per period (a second for the programs'
// warnings and errors, util::log_line), the copies in between counted and said with its next
// writing, "... (repeated N times)". A fault met on every frame (a camera that sends images of
// another size) then costs one line a second, not fifty. Pure: time is an argument.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace tactile::util {

class RepeatLimiter {
 public:
  struct Decision {
    bool write = true;
    std::uint64_t held_back = 0;  // copies not written since it was last written
  };

  explicit RepeatLimiter(std::int64_t period_ns = 1'000'000'000) : period_ns_(period_ns) {}

  // Whether `message`, offered at `now_ns`, is written now. Remembers the kSlots messages offered
  // most recently; one older than those is new again.
  Decision offer(std::string_view message, std::int64_t now_ns);

  static constexpr std::size_t kSlots = 16;

 private:
  struct Slot {
    std::string message;
    std::int64_t written_ns = 0;
    std::int64_t offered_ns = 0;
    std::uint64_t held_back = 0;
    bool used = false;
  };
  std::int64_t period_ns_;
  std::array<Slot, kSlots> slots_{};
};

// " (repeated N times)" for N > 0, else "".
std::string repeated_suffix(std::uint64_t held_back);

}  // namespace tactile::util
