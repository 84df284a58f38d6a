#pragma once

// The rig in real time (docs/system.md, "The rig in real time"): the world and optics of the
// lockstep runner, but the fingertip cameras are GigE Vision cameras (Aravis's fake camera, fed
// with the rendered images), the arm is commanded over the arm link (ROUTER, with a deadman),
// and ground truth is published. sensor_node and hand_node run as separate programs against it,
// unchanged.
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "tactile/rig/lockstep.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/wire/security.hpp"

namespace tactile::rig {

struct RealtimeOptions {
  // One fake GigE Vision camera per fingertip (left, right): each needs its own address.
  std::array<std::string, kFingertips> camera_addresses{"127.0.0.2", "127.0.0.3"};
  std::array<std::string, kFingertips> camera_serials{"TACTILE-L", "TACTILE-R"};
  // Serve the cameras inside this network namespace (camera::run_in_network_namespace: a name
  // under /run/netns or a path), the rest of the rig staying where it runs: the cameras behind
  // a link of their own. Empty: where the rig runs.
  std::string camera_netns;
  // The GVSP packet size rig --write-configs gives sensor_node (`packet_size`, at most the camera
  // link's MTU); 0: sensor_node's default.
  int camera_packet_size = 0;
  std::string arm_endpoint = "tcp://*:5556";    // the arm controller's ROUTER
  std::string truth_endpoint = "tcp://*:5557";  // ground truth PUB; empty: none
  // What the rig watches to score the run: sensor_node's frames and hand_node's events.
  std::vector<std::string> observe_frames{"tcp://127.0.0.1:5555"};
  std::string observe_events = "tcp://127.0.0.1:5558";
  std::optional<wire::ServerSecurity> arm_security;
  std::optional<wire::ClientSecurity> observe_security;  // for the frames (sensor_node's key)
  std::optional<wire::ClientSecurity> observe_events_security;  // hand_node's key
  // The ground-truth PUB as a CURVE server: a subscriber must know its public key.
  std::optional<wire::ServerSecurity> truth_security;
  // The arm holds when it heard nothing from hand_node for this long.
  double deadman_s = 0.04;
  // Each frame is rendered this long before the camera sends it (the fake camera sends at
  // whole multiples of its period on the wall clock, so the instant is known), but at most
  // three quarters of a period: an image published before the previous send instant would go
  // out a period early.
  double render_lead_s = 0.003;
  // A test's hook for the truth's resend path (docs/rig.md, "Joining truth and frames"): every
  // late_every-th frame is not rendered, as if the rig ran late, so both cameras send the image
  // before it again under a new block id. 0: never on purpose.
  std::uint64_t late_every = 0;
  // Give up when no hand_node has spoken this long after the start.
  double wait_for_hand_s = 60.0;
  // Where to write the calibration files of the two simulated sensors (left.yaml, right.yaml);
  // empty: not written.
  std::filesystem::path calibration_dir;
  bool record_series = true;
  // Fresh noise on every pixel of every frame; otherwise only the element disks (everything
  // sensor_node reads) get fresh noise and the rest of the image keeps its noise (far cheaper).
  bool full_noise = false;
  // Called once the cameras serve and the arm controller and ground truth are bound (for a
  // health check: rig --ready-file).
  std::function<void()> on_ready;
};

struct RealtimeCounters {
  std::uint64_t frames_rendered = 0;
  std::uint64_t late_renders = 0;  // a frame rendered after its send instant
  // Images published after their send instant: the cameras had already sent the previous image
  // again, with its old timestamp, so that frame's latency is a period longer.
  std::uint64_t late_publishes = 0;
  std::uint64_t frames_scored = 0;     // measured frames matched with their truth
  std::uint64_t frames_unmatched = 0;  // measured frames whose truth was not (or no longer) known
  std::uint64_t frames_incomplete = 0;
  // Sends of an image whose GroundTruth had gone out already (published after
  // kTruthWaitPeriods): those frames join their truth by camera timestamp only.
  std::uint64_t sends_after_truth = 0;
  std::uint64_t commands = 0;
  std::uint64_t invalid_commands = 0;  // refused: not decodable or a value the arm must not follow
  std::uint64_t deadman_trips = 0;
  std::uint64_t events = 0;
};

struct RealtimeResult {
  // Report (latency_ms filled), series and calibrations, as the lockstep runner gives them.
  LockstepResult run;
  std::uint64_t latency_samples = 0;
  std::vector<double> latency_ms;  // every sample of latency_ms, in arrival order (latency.png)
  RealtimeCounters counters;
};

// Runs until hand_node's task ends (DONE or ABORTED, then the scenario's settle time), the cap
// drops, the scenario's max_time_s passes, or util::stop_requested(). Throws at start-up when a
// camera address, socket or file cannot be used.
RealtimeResult run_realtime(const Scenario& scenario, const RealtimeOptions& options);

// The controller settings of the scenario as a hand_node `controller:` section (YAML), so
// hand_node runs with what the lockstep runner would use.
std::string hand_controller_yaml(const Scenario& scenario);

// Commissioning: writes into `dir` the calibration files of the two simulated sensors
// (left.yaml, right.yaml) and sensor_node.yaml and hand_node.yaml for this scenario and these
// camera addresses, with the default endpoints on loopback.
void write_node_configs(const Scenario& scenario, const std::filesystem::path& dir,
                        const RealtimeOptions& options);

}  // namespace tactile::rig
