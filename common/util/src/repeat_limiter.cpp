#include "tactile/util/repeat_limiter.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace tactile::util {
namespace {

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

// Where the figure that starts at message[i] (a digit) ends: its digits, and a '.' between two.
std::size_t figure_end(std::string_view message, std::size_t i) {
  while (i < message.size() &&
         (is_digit(message[i]) || (message[i] == '.' && i + 1 < message.size() &&
                                   is_digit(message[i + 1]) && is_digit(message[i - 1]))))
    ++i;
  return i;
}

// Whether `message` has the shape `shape` holds: the same text with each figure as one kFigure.
bool same_shape(std::string_view shape, std::string_view message) {
  std::size_t i = 0;
  for (const char c : shape) {
    if (i >= message.size()) return false;
    if (c == RepeatLimiter::kFigure) {
      if (!is_digit(message[i])) return false;
      i = figure_end(message, i);
    } else if (message[i++] != c) {
      return false;
    }
  }
  return i == message.size();
}

void assign_shape(std::string& shape, std::string_view message) {
  shape.clear();
  for (std::size_t i = 0; i < message.size();) {
    if (is_digit(message[i])) {
      shape.push_back(RepeatLimiter::kFigure);
      i = figure_end(message, i);
    } else {
      shape.push_back(message[i++]);
    }
  }
}

}  // namespace

RepeatLimiter::Decision RepeatLimiter::offer(std::string_view message, std::int64_t now_ns) {
  const auto same = std::find_if(slots_.begin(), slots_.end(), [&](const Slot& s) {
    return s.used && same_shape(s.message, message);
  });
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
  assign_shape(slot->message, message);
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
