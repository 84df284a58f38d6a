#pragma once

#include <string>
#include <string_view>

namespace tactile::util {

// The text on one line: control characters (a newline in a file name or key from a broken
// file) escaped as \xNN, so an error message stays the promised one line.
std::string one_line(std::string_view s);

}  // namespace tactile::util
