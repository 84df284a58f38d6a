#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/control/config.hpp"
#include "tactile/control/types.hpp"
#include "tactile/util/realtime.hpp"
#include "tactile/wire/security.hpp"

namespace tactile::hand {

inline constexpr const char* kHandConfigFormat = "tactile-hand/1";

struct FingertipConfig {
  std::string sensor_id;
  std::filesystem::path calibration_path;
  Calibration calibration;    // for element ids and inward normals
  std::vector<Vec3> normals;  // calibration normals, in calibration order
};

// hand_node's configuration file (docs/hand_node.md).
struct HandConfig {
  std::array<FingertipConfig, control::kFingertips> fingertips;
  std::vector<std::string> subscribe{"tcp://127.0.0.1:5555"};
  std::string arm = "tcp://127.0.0.1:5556";
  std::string events;               // PUB endpoint for events; empty: none
  double heartbeat_period_s = 0.1;  // a Heartbeat to the arm controller when idle this long
  double control_period_s = 0.005;  // the controller also runs this often without new frames
  double arm_timeout_s = 1.0;       // no ArmState for this long: warn that the arm is silent
  // Silent this long once heard (no ArmState, no Heartbeat): hold, say so and exit 4; 0: never.
  double arm_lost_s = 5.0;
  // A frame waits at most this long for the other fingertip's frame of the same exposure
  // (received by sensor_node this close together); 0: the controller runs on every frame.
  double pair_window_s = 0.002;
  // The task starts once each fingertip has sent this many whole frames (and the arm answered):
  // a camera's first frames after its stream starts come late and in bursts, and the task's
  // first command should not answer them.
  int start_after_frames = 20;
  control::Config controller;
  // CURVE on every socket (docs/security.md); unset: plain TCP.
  std::optional<wire::ClientSecurity> sensor_security;  // SUB: the sensor_node's public key
  std::optional<wire::ClientSecurity> arm_security;     // DEALER: the arm controller's public key
  // The events PUB, a CURVE server with hand_node's own key pair: a subscriber must know
  // hand_node's public key.
  std::optional<wire::ServerSecurity> events_security;
  // SCHED_FIFO and locked memory for the whole program (docs/deployment.md); default: neither.
  util::RealtimeScheduling realtime;
};

// Loads and checks the file; throws config::ConfigError naming file, line, key and value.
// Calibration paths are relative to the configuration file's folder.
HandConfig load_hand_config(const std::filesystem::path& path, std::vector<std::string>* warnings);

}  // namespace tactile::hand
