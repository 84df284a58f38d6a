#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace tactile::util {

// The text on one line: control characters (a newline in a file name or key from a broken
// file) escaped as \xNN, so an error message stays the promised one line.
std::string one_line(std::string_view s);

// The optimal string alignment distance: insertions, deletions, substitutions and swaps of two
// neighbouring characters each count 1 ("slip_tresh" -> "slip_thresh" is 1, "amr" -> "arm" 1).
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate nearest to `word` by edit_distance() when it is near enough to be a typo of it
// (at most a third of the word's length, at least 2, and less than the word's length), else the
// first candidate that begins with a word of 3 or more characters, else empty. Of equally near
// candidates, the first wins. Used to name "did you mean" in messages.
std::string closest_match(std::string_view word, const std::vector<std::string>& candidates);

}  // namespace tactile::util
