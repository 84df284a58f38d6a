#pragma once

// The YAML configuration loaders take a path: each input is written to a file in a private
// folder that also holds valid calibration files for the names the seeds use (left.yaml,
// right.yaml). The documented promise: a file that cannot be used throws config::ConfigError
// with a one-line message; anything else escaping is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_common.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/config/yaml.hpp"

namespace tactile::fuzz {

class ConfigFolder {
 public:
  ConfigFolder() {
    std::string templ = (std::filesystem::temp_directory_path() / "tactile-fuzz-XXXXXX").string();
    if (::mkdtemp(templ.data()) == nullptr) {
      std::perror("mkdtemp");
      std::abort();
    }
    dir_ = templ;
    config::save_calibration(dir_ / "left.yaml", wire_calibration("left"));
    config::save_calibration(dir_ / "right.yaml", wire_calibration("right"));
  }
  ~ConfigFolder() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  ConfigFolder(const ConfigFolder&) = delete;
  ConfigFolder& operator=(const ConfigFolder&) = delete;

  // Writes the input as `name` in the folder and returns its path.
  std::filesystem::path write(const char* name, const std::uint8_t* data, std::size_t size) const {
    const auto path = dir_ / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    require(static_cast<bool>(out), "cannot write the input file");
    return path;
  }

 private:
  std::filesystem::path dir_;
};

// Runs `load` and enforces the error promise.
template <typename Load>
void expect_loaded_or_config_error(Load&& load) {
  try {
    load();
  } catch (const config::ConfigError& e) {
    const std::string what = e.what();
    require(!what.empty(), "ConfigError without a message");
    if (what.find('\n') != std::string::npos) {
      std::fprintf(stderr, "message: [%s]\n", what.c_str());
      require(false, "ConfigError message is not one line");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "escaped exception (not ConfigError): %s\n", e.what());
    require(false, "an exception other than ConfigError escaped the loader");
  }
}

}  // namespace tactile::fuzz
