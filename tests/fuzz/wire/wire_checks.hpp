#pragma once

// The promises of each wire decoder, checked on every input it accepts.
// SetLogHandler (protobuf 3.21 declares it in this public header): silences protobuf's log.
#include <google/protobuf/stubs/logging.h>

#include <cmath>
#include <cstring>

#include "fuzz_common.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::fuzz {

// Protobuf logs every string field that is not UTF-8 to stderr; at fuzzing rates that drowns
// the findings. (The programs do log them: see docs/reliability.md.)
inline void silence_protobuf_log() {
  google::protobuf::SetLogHandler(nullptr);
}

inline bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// read_tactile_frame: a COMPLETE frame carries exactly the calibration's elements in order with
// every number finite (in the core's units: centroids in pixels), G not negative, and a
// displacement only in contact; other statuses carry nothing.
inline void check_tactile_frame(const v1::TactileFrame& in, const Calibration& cal,
                                wire::DecodeStatus status, const wire::ReceivedFrame& out) {
  if (status != wire::DecodeStatus::kOk) {
    require(status == wire::DecodeStatus::kInvalid, "read_tactile_frame: unexpected status");
    return;
  }
  require(v1::FrameStatus_IsValid(out.header.status), "accepted an unknown frame status");
  require(std::isfinite(out.header.measure_time_us), "accepted a non-finite measure time");
  if (out.header.status != v1::FRAME_STATUS_COMPLETE) {
    require(in.elements_size() == 0, "accepted readings on a frame that is not COMPLETE");
    return;
  }
  require(out.elements.size() == cal.elements.size(), "element count differs from calibration");
  for (std::size_t i = 0; i < out.elements.size(); ++i) {
    const ElementReading& r = out.elements[i];
    require(r.id == cal.elements[i].id, "element id out of calibration order");
    const double values[] = {r.G,     r.x_px,  r.y_px, r.dx_mm, r.dy_mm,
                             r.ux_mm, r.uy_mm, r.fx,   r.fy,    r.fz};
    for (double v : values)
      require(std::isfinite(v), "accepted frame yields a non-finite reading");
    require(r.G >= 0, "accepted a negative G");
    require(!r.has_displacement || r.contact, "displacement out of contact");
  }
}

// read_arm_command: every number finite, speeds and distances not negative, the MoveTo name
// NUL-terminated inside the buffer and pointed to, at most kMaxAnswers answers naming a
// configured fingertip or none.
inline void check_arm_command(const v1::ArmCommand& in, wire::DecodeStatus status,
                              const wire::ReceivedCommand& out) {
  require(out.answers.count <= wire::kMaxAnswers, "too many answers kept");
  for (std::size_t i = 0; i < out.answers.count; ++i) {
    const auto f = out.answers.refs[i].fingertip;
    require(f >= control::kNoFingertip && f < static_cast<int>(control::kFingertips),
            "answer names a fingertip out of range");
  }
  if (status == wire::DecodeStatus::kEmpty) {
    require(in.command_case() == v1::ArmCommand::COMMAND_NOT_SET, "empty but a command is set");
    return;
  }
  if (status != wire::DecodeStatus::kOk) {
    require(status == wire::DecodeStatus::kInvalid, "read_arm_command: unexpected status");
    return;
  }
  const control::Command& c = out.command;
  switch (c.kind) {
    case control::CommandKind::kMoveTo:
      require(in.has_move_to(), "MoveTo without move_to");
      require(c.move_to.name == out.name.data(), "MoveTo name does not point into the command");
      require(std::memchr(out.name.data(), '\0', out.name.size()) != nullptr,
              "MoveTo name not terminated");
      require(finite(c.move_to.target.position_m) && std::isfinite(c.move_to.target.yaw_rad),
              "MoveTo target not finite");
      require(std::isfinite(c.move_to.max_speed_mps) && c.move_to.max_speed_mps >= 0,
              "MoveTo speed not finite or negative");
      require(std::isfinite(c.move_to.max_yaw_rate_rps) && c.move_to.max_yaw_rate_rps >= 0,
              "MoveTo yaw rate not finite or negative");
      break;
    case control::CommandKind::kFingerVelocities:
      require(in.has_finger_velocities(), "FingerVelocities without finger_velocities");
      for (const Vec3& v : c.finger_velocities.velocity_mps)
        require(finite(v), "finger velocity not finite");
      break;
    case control::CommandKind::kOpen:
      require(in.has_open(), "Open without open");
      require(std::isfinite(c.open.speed_mps) && c.open.speed_mps >= 0, "Open speed");
      require(std::isfinite(c.open.distance_m) && c.open.distance_m >= 0, "Open distance");
      break;
    case control::CommandKind::kHold:
      require(in.has_hold(), "Hold without hold");
      break;
    case control::CommandKind::kStop:
      require(in.has_stop(), "Stop without stop");
      break;
    case control::CommandKind::kNone:
      require(false, "accepted command of no kind");
  }
}

// read_arm_state: every number finite, in the state and in the controller's feedback.
inline void check_arm_state(wire::DecodeStatus status, const wire::ArmStateData& out) {
  if (status != wire::DecodeStatus::kOk) {
    require(status == wire::DecodeStatus::kInvalid, "read_arm_state: unexpected status");
    return;
  }
  require(finite(out.wrist.position_m) && std::isfinite(out.wrist.yaw_rad), "wrist not finite");
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    require(finite(out.fingertip_position_m[i]), "fingertip position not finite");
    require(finite(out.fingertip_velocity_mps[i]), "fingertip velocity not finite");
  }
  const control::ArmFeedback f = wire::to_feedback(out);
  require(finite(f.wrist.position_m) && std::isfinite(f.wrist.yaw_rad), "feedback not finite");
}

}  // namespace tactile::fuzz
