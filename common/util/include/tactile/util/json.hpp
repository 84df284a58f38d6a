#pragma once

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace tactile::util {

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
