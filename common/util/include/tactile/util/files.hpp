#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace tactile::util {

// Reads a whole file; throws std::runtime_error naming the file on failure.
std::string read_file(const std::filesystem::path& path);

// Writes a whole file atomically: a temporary file beside it, flushed to disk, then renamed over
// the target, so a reader sees the old file or the new one, never half of one. Creates missing
// parent directories. Throws std::runtime_error naming the file on failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace tactile::util
