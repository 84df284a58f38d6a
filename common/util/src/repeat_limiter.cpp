#include "tactile/util/repeat_limiter.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace tactile::util {

RepeatLimiter::Decision RepeatLimiter::offer(std::string_view message, std::int64_t now_ns) {
  const auto same = std::find_if(slots_.begin(), slots_.end(),
                                 [&](const Slot& s) { return s.used && s.message == message; });
  if (same != slots_.end()) {
    same->offered_ns = now_ns;
    if (now_ns - same->written_ns < period_ns_) {
      ++same->held_back;
      return {false, same->held_back};
    }
    const Decision d{true, same->held_back};
    same->written_ns = now_ns;
    same->held_back = 0;
    return d;
  }
  // A new message takes a free slot, or that of the message offered longest ago.
  const auto slot =
      std::min_element(slots_.begin(), slots_.end(), [](const Slot& a, const Slot& b) {
        if (a.used != b.used) return !a.used;
        return a.offered_ns < b.offered_ns;
      });
  slot->message.assign(message);
  slot->written_ns = now_ns;
  slot->offered_ns = now_ns;
  slot->held_back = 0;
  slot->used = true;
  return {true, 0};
}

std::string repeated_suffix(std::uint64_t held_back) {
  return held_back == 0 ? std::string() : fmt::format(" (repeated {} times)", held_back);
}

}  // namespace tactile::util
