#pragma once

// Malformed, truncated, oversized, wrong-version and mutated messages for bad-input tests,
// drawn from a seeded generator around a valid message.
#include <cstdint>
#include <string>

#include "tactile/util/random.hpp"

namespace tactile::testing {

class Garbage {
 public:
  // `valid`: a well-formed serialised Envelope to mutate.
  Garbage(std::string valid, std::uint64_t seed) : valid_(std::move(valid)), rng_(seed) {}

  // The next bad message (never equal to `valid`).
  std::string next() {
    std::string m;
    switch (rng_.below(6)) {
      case 0: {  // random bytes
        m.resize(rng_.below(512));
        for (char& c : m)
          c = static_cast<char>(rng_.below(256));
        break;
      }
      case 1:  // truncated
        m = valid_.substr(0, rng_.below(valid_.size()));
        break;
      case 2: {  // a few bytes flipped
        m = valid_;
        const auto flips = 1 + rng_.below(8);
        for (std::uint64_t i = 0; i < flips && !m.empty(); ++i) {
          m[rng_.below(m.size())] ^= static_cast<char>(1 + rng_.below(255));
        }
        break;
      }
      case 3: {  // garbage appended
        m = valid_;
        const auto extra = 1 + rng_.below(64);
        for (std::uint64_t i = 0; i < extra; ++i)
          m.push_back(static_cast<char>(rng_.below(256)));
        break;
      }
      case 4:  // wrong schema version: field 1 (varint) set to 2..200, then the valid body
        m = std::string("\x08", 1) + static_cast<char>(2 + rng_.below(120)) + valid_;
        break;
      default:  // empty
        break;
    }
    if (m == valid_) m.push_back('\x01');
    return m;
  }

 private:
  std::string valid_;
  util::Random rng_;
};

}  // namespace tactile::testing
