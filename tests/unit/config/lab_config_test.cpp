// docker/config/lab and docker/systemd cannot rot: every YAML file of the lab examples loads
// with the loader of its format (the programs' own), without a warning, and the systemd units
// name configuration files that exist there.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "hand_config.hpp"
#include "process.hpp"
#include "sensor_config.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/wire/security.hpp"

namespace tactile {
namespace {

namespace fs = std::filesystem;

const fs::path kLab = fs::path(TACTILE_SOURCE_DIR) / "docker" / "config" / "lab";
const fs::path kUnits = fs::path(TACTILE_SOURCE_DIR) / "docker" / "systemd";

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The value of the first top-level "format:" line.
std::string format_of(const fs::path& p) {
  static const std::regex re(R"((^|\n)format:\s*([^\s#]+))");
  std::smatch m;
  const std::string text = read_text(p);
  return std::regex_search(text, m, re) ? m[2].str() : std::string();
}

// The lab folder as installed in /etc/tactile: the files, plus the keys tactile_keygen makes
// (they are never shipped).
class LabConfig : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const auto& e : fs::directory_iterator(kLab))
      fs::copy_file(e.path(), etc_ / e.path().filename());
    if (wire::curve_available()) {
      fs::create_directory(etc_ / "keys");
      for (const char* name : {"sensor", "hand", "arm"})
        wire::write_key_files(etc_ / "keys", name, wire::generate_keypair());
    }
  }
  testing::TempDir etc_;
};

TEST_F(LabConfig, EveryYamlLoadsWithTheLoaderOfItsFormatWithoutWarnings) {
  ASSERT_TRUE(wire::curve_available()) << "the lab examples use CURVE: libzmq without it";
  std::set<std::string> seen;
  int files = 0;
  for (const auto& e : fs::directory_iterator(etc_.path())) {
    const fs::path p = e.path();
    if (p.extension() != ".yaml") continue;
    ++files;
    SCOPED_TRACE(p.filename().string());
    const std::string format = format_of(p);
    seen.insert(format);
    std::vector<std::string> warnings;
    if (format == "tactile-sensor/1") {
      const sensor::SensorConfig c = sensor::load_sensor_config(p, &warnings, etc_ / "state");
      // Secured on the lab network; the bootstrap publishes on 127.0.0.1 only.
      EXPECT_TRUE(c.security.has_value() || c.publish.starts_with("tcp://127.0.0.1:"));
      ASSERT_FALSE(c.cameras.empty());
      for (const sensor::CameraConfig& cam : c.cameras) {
        SCOPED_TRACE(cam.sensor_id);
        EXPECT_FALSE(cam.camera.camera.empty());
        EXPECT_GT(cam.camera.frame_rate_hz, 0.0);
        // A GigE link's MTU is 1500 or 9000: a packet above it never arrives.
        EXPECT_LE(cam.camera.packet_size_bytes, 9000);
        EXPECT_EQ(cam.reference_cache.parent_path(), etc_ / "state");
      }
    } else if (format == "tactile-hand/1") {
      const hand::HandConfig c = hand::load_hand_config(p, &warnings);
      EXPECT_TRUE(c.sensor_security.has_value());
      EXPECT_TRUE(c.arm_security.has_value());
    } else if (format == "tactile-calibration/1") {
      const Calibration c = config::load_calibration(p, &warnings);
      // The bootstrap calibration holds one element; a sensor's, the paper's 41.
      const bool bootstrap = p.filename().string().starts_with("bootstrap");
      EXPECT_EQ(c.elements.size(), bootstrap ? 1u : 41u);
    } else {
      ADD_FAILURE() << "no known format: '" << format << "'";
    }
    EXPECT_THAT(warnings, ::testing::IsEmpty());
  }
  EXPECT_GE(files, 4);
  EXPECT_EQ(seen,
            (std::set<std::string>{"tactile-sensor/1", "tactile-hand/1", "tactile-calibration/1"}));
}

TEST(SystemdUnits, NameLabConfigurationsAndTheStateDirectory) {
  for (const char* unit : {"sensor_node.service", "hand_node.service"}) {
    SCOPED_TRACE(unit);
    const std::string text = read_text(kUnits / unit);
    std::smatch m;
    ASSERT_TRUE(
        std::regex_search(text, m, std::regex(R"(\nExecStart=(\S+) --config /etc/tactile/(\S+))")));
    EXPECT_EQ(fs::path(m[1].str()).filename().string() + ".service", unit);
    EXPECT_TRUE(fs::exists(kLab / m[2].str())) << m[2].str();
    EXPECT_THAT(text, ::testing::HasSubstr("\nRestart=on-failure\n"));
    EXPECT_THAT(text, ::testing::HasSubstr("\nUser=tactile\n"));
  }
  // sensor_node's --state-dir is the directory systemd makes for it.
  const std::string sensor = read_text(kUnits / "sensor_node.service");
  EXPECT_THAT(sensor, ::testing::HasSubstr("--state-dir /var/lib/tactile-sensor"));
  EXPECT_THAT(sensor, ::testing::HasSubstr("\nStateDirectory=tactile-sensor\n"));
}

}  // namespace
}  // namespace tactile
