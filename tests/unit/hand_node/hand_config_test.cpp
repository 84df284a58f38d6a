// hand_node's configuration: pair_window_s, start_after_frames and realtime are read with their
// defaults, and a bad value is refused by a line naming the file, the key and the value.
#include "hand_config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "process.hpp"
#include "tactile/config/yaml.hpp"

namespace tactile::hand {
namespace {

namespace fs = std::filesystem;

const fs::path kLab = fs::path(TACTILE_SOURCE_DIR) / "docker" / "config" / "lab";

class HandConfigFile : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* f : {"left.yaml", "right.yaml"})
      fs::copy_file(kLab / f, dir_ / f);
  }
  fs::path write(const std::string& extra) {
    const fs::path p = dir_ / "hand_node.yaml";
    std::ofstream(p) << "format: tactile-hand/1\n"
                        "fingertips:\n"
                        "  - {sensor_id: left, calibration: left.yaml}\n"
                        "  - {sensor_id: right, calibration: right.yaml}\n"
                     << extra;
    return p;
  }
  // `key: value` is refused by one line naming the file, the key and the value.
  void expect_refused(const std::string& key, const std::string& value) {
    const fs::path p = write(key + ": " + value + "\n");
    try {
      load_hand_config(p, nullptr);
      ADD_FAILURE() << key << ": " << value << " was accepted";
    } catch (const config::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(p.string()), std::string::npos) << what;
      EXPECT_NE(what.find(key), std::string::npos) << what;
      EXPECT_NE(what.find(value), std::string::npos) << what;
    }
  }
  testing::TempDir dir_;
};

TEST_F(HandConfigFile, PairWindowDefaultsOnAndIsRead) {
  std::vector<std::string> warnings;
  EXPECT_DOUBLE_EQ(load_hand_config(write(""), &warnings).pair_window_s, 0.002);
  EXPECT_DOUBLE_EQ(load_hand_config(write("pair_window_s: 0\n"), &warnings).pair_window_s, 0.0);
  EXPECT_DOUBLE_EQ(load_hand_config(write("pair_window_s: 0.0008\n"), &warnings).pair_window_s,
                   0.0008);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
}

// The slip detector is the learned combiner unless the configuration names another.
TEST_F(HandConfigFile, SlipDetectorDefaultsToTheLearnedCombinerAndIsRead) {
  std::vector<std::string> warnings;
  EXPECT_EQ(load_hand_config(write(""), &warnings).controller.slip_detector,
            control::SlipDetectorKind::kLearned);
  EXPECT_EQ(load_hand_config(write("controller:\n  slip_detector: paper\n"), &warnings)
                .controller.slip_detector,
            control::SlipDetectorKind::kPaper);
  const auto field =
      load_hand_config(write("controller:\n  slip_detector: field\n  field_edge_ratio: 0.6\n"),
                       &warnings)
          .controller;
  EXPECT_EQ(field.slip_detector, control::SlipDetectorKind::kField);
  EXPECT_DOUBLE_EQ(field.field_edge_ratio, 0.6);
}

// The grip is the paper's unless the configuration names the margin grip, whose parameters it
// reads beside it.
TEST_F(HandConfigFile, GripDefaultsToThePapersAndIsRead) {
  std::vector<std::string> warnings;
  EXPECT_EQ(load_hand_config(write(""), &warnings).controller.grip, control::GripKind::kPaper);
  const auto margin =
      load_hand_config(write("controller:\n  grip: margin\n  grip_margin: 0.3\n"), &warnings)
          .controller;
  EXPECT_EQ(margin.grip, control::GripKind::kMargin);
  EXPECT_DOUBLE_EQ(margin.grip_margin, 0.3);
}

TEST_F(HandConfigFile, StartAfterFramesDefaultsTo20AndIsRead) {
  std::vector<std::string> warnings;
  EXPECT_EQ(load_hand_config(write(""), &warnings).start_after_frames, 20);
  EXPECT_EQ(load_hand_config(write("start_after_frames: 1\n"), &warnings).start_after_frames, 1);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  for (const char* bad : {"0", "-3", "2.5", "many", "10001"})
    expect_refused("start_after_frames", bad);
}

// hand_node gives up on an arm controller silent for arm_lost_s (5 s); 0 never does; the time
// is at least arm_timeout_s, the warning's.
TEST_F(HandConfigFile, ArmLostDefaultsToFiveSecondsAndIsRead) {
  std::vector<std::string> warnings;
  EXPECT_DOUBLE_EQ(load_hand_config(write(""), &warnings).arm_lost_s, 5.0);
  EXPECT_DOUBLE_EQ(load_hand_config(write("arm_lost_s: 0\n"), &warnings).arm_lost_s, 0.0);
  EXPECT_DOUBLE_EQ(
      load_hand_config(write("arm_timeout_s: 0.2\narm_lost_s: 0.5\n"), &warnings).arm_lost_s, 0.5);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  for (const char* bad : {"-1", "0.5", "4000", "soon"})
    expect_refused("arm_lost_s", bad);
}

TEST_F(HandConfigFile, BadPairWindowNamesFileKeyAndValue) {
  for (const char* bad : {"-0.5", "2", "soon"})
    expect_refused("pair_window_s", bad);
}

TEST_F(HandConfigFile, RealtimeIsOffByDefaultAndIsRead) {
  std::vector<std::string> warnings;
  const util::RealtimeScheduling off = load_hand_config(write(""), &warnings).realtime;
  EXPECT_EQ(off.priority, 0);
  EXPECT_FALSE(off.lock_memory);
  const util::RealtimeScheduling on =
      load_hand_config(write("realtime: {priority: 20, lock_memory: true}\n"), &warnings).realtime;
  EXPECT_EQ(on.priority, 20);
  EXPECT_TRUE(on.lock_memory);
  const util::RealtimeScheduling lock_only =
      load_hand_config(write("realtime: {lock_memory: true}\n"), &warnings).realtime;
  EXPECT_EQ(lock_only.priority, 0);
  EXPECT_TRUE(lock_only.lock_memory);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
}

TEST_F(HandConfigFile, AMisspeltKeyIsRefusedAtItsLineWithTheClosestKey) {
  const auto refused = [&](const std::string& extra, const std::string& expect) {
    const fs::path p = write(extra);
    try {
      load_hand_config(p, nullptr);
      ADD_FAILURE() << extra << " was accepted";
    } catch (const config::ConfigError& e) {
      EXPECT_EQ(std::string(e.what()), p.string() + expect);
    }
  };
  refused("realtime: {priority: 5, lock: true}\n",
          ":5: unknown key 'lock' in 'realtime' (did you mean 'lock_memory'?)");
  refused("pair_windw_s: 0.001\n",
          ":5: unknown key 'pair_windw_s' (did you mean 'pair_window_s'?)");
  refused("realtime: {sched: fifo}\n",
          ":5: unknown key 'sched' in 'realtime' (known keys: priority, lock_memory)");
  refused("controller:\n  f1_n: 0.5\n  twist_dr_facter: 2\n",
          ":7: unknown key 'twist_dr_facter' in 'controller' (did you mean 'twist_dr_factor'?)");
  refused("controller:\n  slip_detector: fields\n",
          ":6: key 'controller.slip_detector': must be paper, field or learned, is 'fields'");
  refused("controller:\n  grip: firm\n",
          ":6: key 'controller.grip': must be paper or margin, is 'firm'");
}

TEST_F(HandConfigFile, BadRealtimeNamesFileKeyAndValue) {
  const auto refused = [&](const std::string& section, const std::string& key,
                           const std::string& value) {
    const fs::path p = write("realtime: " + section + "\n");
    try {
      load_hand_config(p, nullptr);
      ADD_FAILURE() << section << " was accepted";
    } catch (const config::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(p.string()), std::string::npos) << what;
      EXPECT_NE(what.find("'" + key + "'"), std::string::npos) << what;
      EXPECT_NE(what.find(value), std::string::npos) << what;
    }
  };
  for (const char* bad : {"0", "99", "-1", "2.5", "high"})
    refused(std::string("{priority: ") + bad + "}", "realtime.priority", bad);
  refused("{priority: 10, lock_memory: maybe}", "realtime.lock_memory", "maybe");
  refused("10", "realtime", "10");
}

}  // namespace
}  // namespace tactile::hand
