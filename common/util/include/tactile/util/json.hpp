#pragma once

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <string_view>

namespace tactile::util {

// JSON string literal with quotes and escapes.
std::string json_quote(std::string_view s);

// Shortest decimal that reads back as the same double; non-finite values become null (the
// cores never produce them, but a writer must not emit invalid JSON).
inline void json_number(std::string& out, double v) {
  if (std::isfinite(v)) {
    fmt::format_to(std::back_inserter(out), "{}", v);
  } else {
    out += "null";
  }
}

}  // namespace tactile::util
