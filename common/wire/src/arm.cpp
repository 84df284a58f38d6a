#include "tactile/wire/arm.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tactile::wire {
namespace {

void set_vec(const Vec3& v, v1::Vec3& out) {
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
}

Vec3 get_vec(const v1::Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void set_pose(const control::WristPose& p, v1::WristPose& out) {
  set_vec(p.position_m, *out.mutable_position_m());
  out.set_yaw_rad(p.yaw_rad);
}

control::WristPose get_pose(const v1::WristPose& p) {
  return {get_vec(p.position_m()), p.yaw_rad()};
}

bool finite(const control::WristPose& p) {
  return finite(p.position_m) && std::isfinite(p.yaw_rad);
}

int fingertip_of(const std::string& sensor_id, const FingertipIds& ids) {
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] == sensor_id) return static_cast<int>(i);
  }
  return -1;
}

// Grows or shrinks `out` to `n` elements, keeping the ones it holds: no allocation once warm.
template <typename T>
void resize(google::protobuf::RepeatedPtrField<T>& out, std::size_t n) {
  while (out.size() > static_cast<int>(n))
    out.RemoveLast();
  while (out.size() < static_cast<int>(n))
    out.Add();
}

void fill_answers(const Answers& answers, const FingertipIds& ids,
                  google::protobuf::RepeatedPtrField<v1::FrameRef>& out) {
  resize(out, answers.count);
  for (std::size_t i = 0; i < answers.count; ++i) {
    const FrameRef& r = answers.refs[i];
    v1::FrameRef& f = out[static_cast<int>(i)];
    if (r.fingertip >= 0 && static_cast<std::size_t>(r.fingertip) < ids.size()) {
      f.set_sensor_id(ids[static_cast<std::size_t>(r.fingertip)]);
    } else {
      f.clear_sensor_id();
    }
    f.set_sequence(r.sequence);
    f.set_camera_timestamp_ns(r.camera_timestamp_ns);
  }
}

}  // namespace

void fill_arm_command(const control::Command& c, std::uint64_t sequence, std::int64_t send_ns,
                      const Answers& answers, const FingertipIds& ids, v1::ArmCommand& out) {
  out.set_sequence(sequence);
  out.set_send_timestamp_ns(send_ns);
  fill_answers(answers, ids, *out.mutable_answers());
  switch (c.kind) {
    case control::CommandKind::kMoveTo: {
      v1::MoveTo& m = *out.mutable_move_to();
      m.set_segment_id(c.move_to.segment_id);
      m.set_name(c.move_to.name != nullptr ? c.move_to.name : "");
      set_pose(c.move_to.target, *m.mutable_target());
      m.set_max_speed_mps(c.move_to.max_speed_mps);
      m.set_max_yaw_rate_rps(c.move_to.max_yaw_rate_rps);
      m.set_keep_finger_velocities(c.move_to.keep_finger_velocities);
      break;
    }
    case control::CommandKind::kFingerVelocities: {
      auto* fingers = out.mutable_finger_velocities()->mutable_fingers();
      resize(*fingers, ids.size());
      for (std::size_t i = 0; i < ids.size(); ++i) {
        v1::FingerVelocity& f = (*fingers)[static_cast<int>(i)];
        f.set_sensor_id(ids[i]);
        set_vec(c.finger_velocities.velocity_mps[i], *f.mutable_velocity_mps());
      }
      break;
    }
    case control::CommandKind::kHold:
      out.mutable_hold();
      break;
    case control::CommandKind::kOpen:
      out.mutable_open()->set_speed_mps(c.open.speed_mps);
      out.mutable_open()->set_distance_m(c.open.distance_m);
      break;
    case control::CommandKind::kStop:
      out.mutable_stop();
      break;
    case control::CommandKind::kNone:
      out.clear_command();
      break;
  }
}

DecodeStatus read_arm_command(const v1::ArmCommand& in, const FingertipIds& ids,
                              ReceivedCommand& out) noexcept {
  out.sequence = in.sequence();
  out.send_timestamp_ns = in.send_timestamp_ns();
  out.answers = {};
  for (const v1::FrameRef& r : in.answers()) {
    const int k = fingertip_of(r.sensor_id(), ids);
    out.answers.add({static_cast<std::int8_t>(k), r.sequence(), r.camera_timestamp_ns()});
  }
  control::Command& c = out.command;
  c = control::Command{};
  switch (in.command_case()) {
    case v1::ArmCommand::kMoveTo: {
      const v1::MoveTo& m = in.move_to();
      c.kind = control::CommandKind::kMoveTo;
      c.move_to.segment_id = m.segment_id();
      const std::size_t n = std::min(m.name().size(), kMaxNameLength);
      std::memcpy(out.name.data(), m.name().data(), n);
      out.name[n] = '\0';
      c.move_to.name = out.name.data();
      c.move_to.target = get_pose(m.target());
      c.move_to.max_speed_mps = m.max_speed_mps();
      c.move_to.max_yaw_rate_rps = m.max_yaw_rate_rps();
      c.move_to.keep_finger_velocities = m.keep_finger_velocities();
      if (!finite(c.move_to.target) || !std::isfinite(c.move_to.max_speed_mps) ||
          !std::isfinite(c.move_to.max_yaw_rate_rps) || c.move_to.max_speed_mps < 0 ||
          c.move_to.max_yaw_rate_rps < 0) {
        return DecodeStatus::kInvalid;
      }
      return DecodeStatus::kOk;
    }
    case v1::ArmCommand::kFingerVelocities: {
      c.kind = control::CommandKind::kFingerVelocities;
      std::array<bool, control::kFingertips> seen{};
      for (const v1::FingerVelocity& f : in.finger_velocities().fingers()) {
        const int k = fingertip_of(f.sensor_id(), ids);
        if (k < 0 || seen[static_cast<std::size_t>(k)]) return DecodeStatus::kInvalid;
        seen[static_cast<std::size_t>(k)] = true;
        const Vec3 v = get_vec(f.velocity_mps());
        if (!finite(v)) return DecodeStatus::kInvalid;
        c.finger_velocities.velocity_mps[static_cast<std::size_t>(k)] = v;
      }
      return DecodeStatus::kOk;
    }
    case v1::ArmCommand::kHold:
      c.kind = control::CommandKind::kHold;
      return DecodeStatus::kOk;
    case v1::ArmCommand::kOpen:
      c.kind = control::CommandKind::kOpen;
      c.open.speed_mps = in.open().speed_mps();
      c.open.distance_m = in.open().distance_m();
      if (!std::isfinite(c.open.speed_mps) || !std::isfinite(c.open.distance_m) ||
          c.open.speed_mps < 0 || c.open.distance_m < 0) {
        return DecodeStatus::kInvalid;
      }
      return DecodeStatus::kOk;
    case v1::ArmCommand::kStop:
      c.kind = control::CommandKind::kStop;
      return DecodeStatus::kOk;
    case v1::ArmCommand::COMMAND_NOT_SET:
      return DecodeStatus::kEmpty;
  }
  return DecodeStatus::kInvalid;
}

void fill_arm_state(const ArmStateData& s, const FingertipIds& ids, v1::ArmState& out) {
  out.set_time_ns(s.time_ns);
  set_pose(s.wrist, *out.mutable_wrist());
  auto* tips = out.mutable_fingertips();
  resize(*tips, ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    v1::Fingertip& t = (*tips)[static_cast<int>(i)];
    t.set_sensor_id(ids[i]);
    set_vec(s.fingertip_position_m[i], *t.mutable_position_m());
    set_vec(s.fingertip_velocity_mps[i], *t.mutable_velocity_mps());
  }
  out.set_active_segment_id(s.active_segment_id);
  out.set_segment_done(s.segment_done);
  out.clear_faults();
  if (s.deadman) out.add_faults(v1::ARM_FAULT_DEADMAN);
  if (s.limit) out.add_faults(v1::ARM_FAULT_LIMIT);
  if (s.invalid_command) out.add_faults(v1::ARM_FAULT_INVALID_COMMAND);
  out.set_last_command_sequence(s.last_command_sequence);
  out.set_holding(s.holding);
}

DecodeStatus read_arm_state(const v1::ArmState& in, const FingertipIds& ids,
                            ArmStateData& out) noexcept {
  out.time_ns = in.time_ns();
  out.wrist = get_pose(in.wrist());
  if (!finite(out.wrist)) return DecodeStatus::kInvalid;
  for (const v1::Fingertip& t : in.fingertips()) {
    const int k = fingertip_of(t.sensor_id(), ids);
    if (k < 0) return DecodeStatus::kInvalid;
    const Vec3 p = get_vec(t.position_m());
    const Vec3 v = get_vec(t.velocity_mps());
    if (!finite(p) || !finite(v)) return DecodeStatus::kInvalid;
    out.fingertip_position_m[static_cast<std::size_t>(k)] = p;
    out.fingertip_velocity_mps[static_cast<std::size_t>(k)] = v;
  }
  out.active_segment_id = in.active_segment_id();
  out.segment_done = in.segment_done();
  out.holding = in.holding();
  out.deadman = out.limit = out.invalid_command = false;
  for (int f : in.faults()) {
    out.deadman = out.deadman || f == v1::ARM_FAULT_DEADMAN;
    out.limit = out.limit || f == v1::ARM_FAULT_LIMIT;
    out.invalid_command = out.invalid_command || f == v1::ARM_FAULT_INVALID_COMMAND;
  }
  out.last_command_sequence = in.last_command_sequence();
  return DecodeStatus::kOk;
}

control::ArmFeedback to_feedback(const ArmStateData& s) {
  control::ArmFeedback f;
  f.wrist = s.wrist;
  f.active_segment_id = s.active_segment_id;
  f.segment_done = s.segment_done;
  f.holding = s.holding;
  f.deadman = s.deadman;
  f.fingertip_position_m = s.fingertip_position_m;
  return f;
}

v1::EventKind to_proto(control::EventKind kind) {
  // The control core mirrors the wire's numbering (types.hpp); a test pins every pair.
  return static_cast<v1::EventKind>(static_cast<int>(kind));
}

std::optional<control::Phase> phase_from_string(std::string_view name) {
  for (int p = 0; p <= static_cast<int>(control::Phase::kAborted); ++p) {
    const auto phase = static_cast<control::Phase>(p);
    if (name == control::to_string(phase)) return phase;
  }
  return std::nullopt;
}

void fill_event(const control::Event& e, std::int64_t time_ns, const Answers& answers,
                const FingertipIds& ids, v1::Event& out) {
  out.set_time_ns(time_ns);
  out.set_kind(to_proto(e.kind));
  out.set_phase(control::to_string(e.phase));
  out.set_cycle(e.cycle);
  if (e.fingertip >= 0 && static_cast<std::size_t>(e.fingertip) < ids.size()) {
    out.set_sensor_id(ids[static_cast<std::size_t>(e.fingertip)]);
  } else {
    out.clear_sensor_id();
  }
  out.set_element_id(e.has_element ? e.element_id : 0);
  out.set_value(std::isfinite(e.value) ? e.value : 0.0);
  out.set_text(e.text != nullptr ? e.text : "");
  fill_answers(answers, ids, *out.mutable_answers());
}

void fill_decision(const control::ControllerOutput& output, std::int64_t time_ns,
                   const Answers& answers,
                   const std::array<std::int64_t, control::kFingertips>& received_ns,
                   std::uint64_t command_sequence, const FingertipIds& ids, v1::Decision& out) {
  out.set_time_ns(time_ns);
  fill_answers(answers, ids, *out.mutable_answers());
  for (std::size_t i = 0; i < answers.count; ++i) {
    const auto k = answers.refs[i].fingertip;
    const bool known = k >= 0 && static_cast<std::size_t>(k) < received_ns.size();
    (*out.mutable_answers())[static_cast<int>(i)].set_receive_timestamp_ns(
        known ? received_ns[static_cast<std::size_t>(k)] : 0);
  }
  out.set_phase(control::to_string(output.phase));
  out.set_command_sequence(command_sequence);
  out.set_slip_detector(control::to_string(output.slip_detector));
  auto& tips = *out.mutable_fingertips();
  resize(tips, ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const control::FingertipFlags& f = output.flags.fingertip[i];
    v1::FingertipDecision& d = tips[static_cast<int>(i)];
    d.set_sensor_id(ids[i]);
    d.set_touch(f.touch);
    d.set_slip(f.slip);
    d.set_over(f.over);
    d.set_slipping_elements(f.slipping_elements);
    auto& slipping = *d.mutable_slipping_element_ids();
    slipping.Clear();  // keeps its capacity: no allocation once warm
    const std::size_t named = std::min<std::size_t>(f.slipping_elements, f.slipping_ids.size());
    for (std::size_t k = 0; k < named; ++k)
      slipping.Add(f.slipping_ids[k]);
    d.set_max_fz_n(std::isfinite(f.max_fz_n) ? f.max_fz_n : 0.0);
  }
}

}  // namespace tactile::wire
