#pragma once

// The YAML configuration loaders take a path: each input is written to a file in a folder that
// also holds valid calibration files for the names the seeds use (left.yaml, right.yaml). The
// documented promise: a file that cannot be used throws config::ConfigError with a one-line
// message; anything else escaping is a finding.
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

// One folder, config-inputs/ in the working directory (the build tree under ctest and
// run-wire-fuzz), for every run of the configuration targets, so a run that aborts on a finding
// leaves at most its own input file behind; it holds valid calibration files for the names the
// seeds use, and each process writes its inputs to a file of its own there.
class ConfigFolder {
 public:
  ConfigFolder() : dir_(std::filesystem::current_path() / "config-inputs") {
    std::filesystem::create_directories(dir_);
    const std::string me = std::to_string(::getpid());
    for (const char* id : {"left", "right"}) {
      // Written aside and renamed, so another process never reads half a file.
      const auto aside = dir_ / (std::string(id) + "." + me + ".tmp");
      config::save_calibration(aside, wire_calibration(id));
      std::filesystem::rename(aside, dir_ / (std::string(id) + ".yaml"));
    }
    input_ = dir_ / ("input-" + me + ".yaml");
  }
  ~ConfigFolder() {
    std::error_code ec;
    std::filesystem::remove(input_, ec);
  }
  ConfigFolder(const ConfigFolder&) = delete;
  ConfigFolder& operator=(const ConfigFolder&) = delete;

  // Writes the input to this process's file in the folder and returns its path.
  const std::filesystem::path& write(const std::uint8_t* data, std::size_t size) const {
    std::ofstream out(input_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    require(static_cast<bool>(out), "cannot write the input file");
    return input_;
  }

 private:
  std::filesystem::path dir_;
  std::filesystem::path input_;
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
