#pragma once

// hand_node's loop: TactileFrames in, the control core, ArmCommands out (docs/hand_node.md).
#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "arm_link.hpp"
#include "frame_pairing.hpp"
#include "hand_config.hpp"
#include "tactile/control/controller.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/sockets.hpp"
#include "tactile/wire/tactile_frame.hpp"
#include "tactile_freshness.hpp"
#include "task_start.hpp"

namespace tactile::hand {

struct HandCounters {
  std::array<std::uint64_t, control::kFingertips> frames{};  // whole frames used
  std::array<std::uint64_t, control::kFingertips>
      incomplete{};                    // frames with another status: skipped
  std::uint64_t undecodable = 0;       // malformed, wrong version, invalid values, unknown sensor
  std::uint64_t commands = 0;          // ArmCommands sent
  std::uint64_t commands_blocked = 0;  // could not be queued (arm controller absent)
  std::uint64_t arm_states = 0;
  std::uint64_t events = 0;
  std::uint64_t stale_holds = 0;
  std::uint64_t unpaired =
      0;  // frames whose other fingertip's frame did not come within pair_window_s
};

// kArmLost: the arm controller was silent for arm_lost_s; a Hold went out.
enum class Outcome { kDone, kAborted, kStopped, kArmLost };

class HandNode {
 public:
  HandNode(HandConfig cfg, zmq::context_t& ctx);

  // Runs until the task ends, util::stop_requested() (a Stop goes to the arm) or the arm
  // controller is silent for arm_lost_s (a Hold goes to it).
  Outcome run();
  const HandCounters& counters() const { return counters_; }

 private:
  // now_ns: the loop's reading of the monotonic clock for this turn (docs/architecture.md, rule 5).
  void on_topic_message(std::int64_t now_ns);
  void on_arm_message(std::int64_t now_ns);
  void step(std::int64_t now_ns, FramePairing::Fresh fresh);
  // names_frames: the command answers the latest frames (it was computed from them); a Stop on
  // a signal answers none.
  void send_command(const control::Command& c, std::int64_t now_ns, bool names_frames = true);
  void send_heartbeat(std::int64_t now_ns);
  // False: the arm link could not queue it (the arm controller is absent); counted.
  bool send_envelope();
  wire::Answers answers() const;
  bool ready(std::int64_t now_ns);
  // How long the loop may wait for a message at now_ns: until the next control step, a waiting
  // frame's window or a heartbeat, at most 50 ms.
  std::chrono::milliseconds poll_wait(std::int64_t now_ns) const;
  // The arm link's part of a turn: a heartbeat when due, the arm controller silent or lost.
  // False: it is lost (a Hold went out).
  bool tend_arm_link(std::int64_t now_ns);

  HandConfig cfg_;
  wire::FingertipIds ids_;
  wire::Subscriber sub_;
  wire::Dealer arm_;
  std::optional<wire::Publisher> events_;
  control::GraspMoveTwistController controller_;
  FramePairing pairing_;
  ArmLink link_;
  TaskStart start_;
  TactileFreshness freshness_;
  const std::int64_t period_ns_;  // control_period_s

  // Reused buffers: the per-frame path allocates nothing once they have grown.
  wire::TopicMessage msg_;
  std::vector<std::uint8_t> arm_buf_;
  wire::EnvelopeDecoder decoder_;
  v1::Envelope out_;
  v1::Envelope event_env_;
  v1::Envelope decision_env_;  // one Decision per step on fresh frames (topic "decision")
  std::string out_bytes_;
  std::array<wire::ReceivedFrame, control::kFingertips> frames_;
  wire::ReceivedCommand unused_;

  std::array<std::int64_t, control::kFingertips> received_ns_{};  // CLOCK_REALTIME
  wire::ArmStateData arm_state_;
  std::int64_t last_update_ns_ = 0;
  std::uint64_t command_sequence_ = 0;
  bool stale_ = false;
  HandCounters counters_;
};

}  // namespace tactile::hand
