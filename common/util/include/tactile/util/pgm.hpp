#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "tactile/image.hpp"

namespace tactile::util {

// Binary PGM (P5). maxval up to 255 gives Mono8; 256 to 65535 gives Mono16 (big-endian in the
// file, host-endian in memory). Errors throw std::runtime_error naming `source` and the fault.
Image decode_pgm(std::string_view bytes, const std::string& source);
Image read_pgm(const std::filesystem::path& path);
std::string encode_pgm(const ImageView& image);
// Atomic (see write_file_atomic).
void write_pgm(const std::filesystem::path& path, const ImageView& image);

}  // namespace tactile::util
