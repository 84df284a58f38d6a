#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"

namespace tactile::config {

// Reads a calibration file (docs/calibration.md) and checks every rule; a broken rule
// throws ConfigError naming the file, line, key and element. Unknown keys are tolerated (the
// format grows by adding keys) and listed in `warnings` when given.
Calibration parse_calibration(const std::string& text, const std::string& source,
                              std::vector<std::string>* warnings = nullptr);
Calibration load_calibration(const std::filesystem::path& path,
                             std::vector<std::string>* warnings = nullptr);

// The same format back; numbers keep full precision, so parse(format(c)) == c.
std::string format_calibration(const Calibration& cal);
// Validates, then writes atomically.
void save_calibration(const std::filesystem::path& path, const Calibration& cal);

}  // namespace tactile::config
