#pragma once

// ArmCommand, ArmState and Event <-> control core types. Pure functions: no sockets, no clocks.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "tactile/control/types.hpp"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/envelope.hpp"

namespace tactile::wire {

inline constexpr std::size_t kMaxAnswers = 4;
inline constexpr std::size_t kMaxIdLength = 32;    // sensor ids on the wire
inline constexpr std::size_t kMaxNameLength = 16;  // MoveTo names

// The sensor ids of fingertip 0 and 1 ("left", "right" by default).
using FingertipIds = std::array<std::string, control::kFingertips>;

// A TactileFrame named by a command or an event.
struct FrameRef {
  std::int8_t fingertip = control::kNoFingertip;  // index into FingertipIds
  std::uint64_t sequence = 0;
  std::int64_t camera_timestamp_ns = 0;
};

struct Answers {
  std::array<FrameRef, kMaxAnswers> refs{};
  std::size_t count = 0;
  void add(const FrameRef& r) {
    if (count < kMaxAnswers) refs[count++] = r;
  }
};

// --- ArmCommand ----------------------------------------------------------------------------

void fill_arm_command(const control::Command& command, std::uint64_t sequence, std::int64_t send_ns,
                      const Answers& answers, const FingertipIds& ids, v1::ArmCommand& out);

// What the arm controller takes from an ArmCommand. `command.move_to.name` points into `name`.
struct ReceivedCommand {
  std::uint64_t sequence = 0;
  std::int64_t send_timestamp_ns = 0;
  control::Command command;
  std::array<char, kMaxNameLength + 1> name{};
  Answers answers;
};

// Checks and converts: every number finite, speeds not negative, finger velocities named by the
// configured ids. kInvalid otherwise. Never throws, never allocates. The returned command's
// move_to.name points into out.name, so `out` must outlive its use.
DecodeStatus read_arm_command(const v1::ArmCommand& in, const FingertipIds& ids,
                              ReceivedCommand& out) noexcept;

// --- ArmState ------------------------------------------------------------------------------

struct ArmStateData {
  std::int64_t time_ns = 0;
  control::WristPose wrist;
  std::array<Vec3, control::kFingertips> fingertip_position_m{};
  std::array<Vec3, control::kFingertips> fingertip_velocity_mps{};
  std::uint32_t active_segment_id = 0;
  bool segment_done = false;
  bool holding = false;
  bool deadman = false;
  bool limit = false;
  bool invalid_command = false;
  std::uint64_t last_command_sequence = 0;
};

void fill_arm_state(const ArmStateData& state, const FingertipIds& ids, v1::ArmState& out);
DecodeStatus read_arm_state(const v1::ArmState& in, const FingertipIds& ids,
                            ArmStateData& out) noexcept;
// The controller's view of an arm state.
control::ArmFeedback to_feedback(const ArmStateData& state);

// --- Event ---------------------------------------------------------------------------------

void fill_event(const control::Event& event, std::int64_t time_ns, const Answers& answers,
                const FingertipIds& ids, v1::Event& out);

// --- Decision ------------------------------------------------------------------------------

// The fresh frames a controller step ran on (`answers`, with when each arrived, indexed by
// fingertip: `received_ns`), what it decided (`output`'s phase and flags) and the ArmCommand it
// sent (`command_sequence`, 0 for none). Reuses `out`'s storage: no allocation once warm.
void fill_decision(const control::ControllerOutput& output, std::int64_t time_ns,
                   const Answers& answers,
                   const std::array<std::int64_t, control::kFingertips>& received_ns,
                   std::uint64_t command_sequence, const FingertipIds& ids, v1::Decision& out);

v1::EventKind to_proto(control::EventKind kind);
// The control phase named by an Event's `phase` text (control::to_string); nullopt if none.
std::optional<control::Phase> phase_from_string(std::string_view name);

}  // namespace tactile::wire
