// Writes the seed corpora of the wire and configuration fuzz targets: valid messages made with
// the wire's own fill_* functions, and valid configuration files.
//   tactile_fuzz_wire_seeds OUT_DIR
// makes OUT_DIR/{envelope,tactile_frame,arm_command,arm_state,sensor_config,hand_config}/ and
// OUT_DIR/config.dict.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "tactile/config/controller_file.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace {

using namespace tactile;
namespace fs = std::filesystem;

class Corpus {
 public:
  Corpus(const fs::path& root, const char* name) : dir_(root / name) {
    fs::create_directories(dir_);
  }
  void add(const std::string& bytes) {
    const fs::path file = dir_ / ("seed-" + std::to_string(count_++));
    std::ofstream(file, std::ios::binary) << bytes;
  }

 private:
  fs::path dir_;
  int count_ = 0;
};

std::string serialized(const google::protobuf::Message& m) {
  std::string s;
  m.SerializeToString(&s);
  return s;
}

std::vector<v1::TactileFrame> tactile_frames() {
  const Calibration cal = fuzz::wire_calibration();
  std::vector<ElementReading> rs(cal.elements.size());
  for (std::size_t i = 0; i < rs.size(); ++i) {
    ElementReading& r = rs[i];
    r.id = cal.elements[i].id;
    r.contact = i % 2 == 0;
    r.G = r.contact ? 5321.0 + 100.0 * static_cast<double>(i) : 12.0;
    if (r.contact) {
      r.x_px = cal.elements[i].center_px.x + 0.3;
      r.y_px = cal.elements[i].center_px.y - 0.2;
      r.has_displacement = true;
      r.dx_mm = 0.005;
      r.dy_mm = -0.003;
      r.ux_mm = 0.0075;
      r.uy_mm = -0.005;
      r.fx = 0.018;
      r.fy = -0.0125;
      r.fz = 0.53;
    }
  }
  std::vector<v1::TactileFrame> out;
  const v1::FrameStatus statuses[] = {v1::FRAME_STATUS_COMPLETE, v1::FRAME_STATUS_MISSING_PACKETS,
                                      v1::FRAME_STATUS_NO_REFERENCE, v1::FRAME_STATUS_TIMEOUT};
  std::uint64_t sequence = 0;
  for (v1::FrameStatus status : statuses) {
    wire::FrameHeader h;
    h.sequence = sequence++;
    h.camera_frame_id = 65535;
    h.camera_timestamp_ns = 1'700'000'000'000'000'000;
    h.receive_timestamp_ns = h.camera_timestamp_ns + 400'000;
    h.publish_timestamp_ns = h.receive_timestamp_ns + 90'000;
    h.status = status;
    h.nominal_period_ns = 10'000'000;
    h.frames_skipped = status == v1::FRAME_STATUS_COMPLETE ? 0 : 2;
    h.measure_time_us = 42.5;
    out.emplace_back();
    wire::fill_tactile_frame(cal.sensor_id, h, rs, cal.mm_per_px, out.back());
  }
  return out;
}

std::vector<v1::ArmCommand> arm_commands() {
  wire::Answers answers;
  answers.add({0, 41, 1'700'000'000'000'000'000});
  answers.add({1, 40, 1'700'000'000'000'000'000});
  std::vector<control::Command> commands;
  control::MoveTo m;
  m.segment_id = 3;
  m.name = "MOVE3";
  m.target = {{0.35, -0.10, 0.30}, 0.5};
  m.max_speed_mps = 0.05;
  m.max_yaw_rate_rps = 0.5;
  m.keep_finger_velocities = true;
  commands.push_back(control::Command::move(m));
  control::FingerVelocities v;
  v.velocity_mps[0] = {0, 0, 0.002};
  v.velocity_mps[1] = {0.0005, -0.0005, 0.002};
  commands.push_back(control::Command::velocities(v));
  commands.push_back(control::Command::hold());
  commands.push_back(control::Command::open_fingers({0.005, 0.01}));
  commands.push_back(control::Command::stop());
  std::vector<v1::ArmCommand> out;
  std::uint64_t sequence = 1;
  for (const auto& c : commands) {
    out.emplace_back();
    wire::fill_arm_command(c, sequence++, 1'700'000'000'000'000'000, answers, fuzz::kFingertipIds,
                           out.back());
  }
  return out;
}

std::vector<v1::ArmState> arm_states() {
  wire::ArmStateData s;
  s.time_ns = 1'700'000'000'000'000'000;
  s.wrist = {{0.35, -0.10, 0.25}, 0.1};
  s.fingertip_position_m = {Vec3{-0.02, 0, 0}, Vec3{0.02, 0, 0}};
  s.fingertip_velocity_mps = {Vec3{0, 0, 0.001}, Vec3{0, 0, 0.001}};
  s.active_segment_id = 3;
  s.last_command_sequence = 17;
  std::vector<v1::ArmState> out;
  out.emplace_back();
  wire::fill_arm_state(s, fuzz::kFingertipIds, out.back());
  s.segment_done = true;
  s.holding = true;
  s.deadman = true;
  s.limit = true;
  s.invalid_command = true;
  out.emplace_back();
  wire::fill_arm_state(s, fuzz::kFingertipIds, out.back());
  return out;
}

std::vector<v1::Envelope> other_envelopes() {
  std::vector<v1::Envelope> out;
  {
    v1::Envelope e;
    v1::SensorStats& s = *e.mutable_sensor_stats();
    s.set_sensor_id("left");
    s.set_time_ns(1'700'000'000'000'000'000);
    s.set_frames(1000);
    s.set_frames_complete(990);
    s.set_frames_incomplete(10);
    s.set_missing_packets(12);
    s.set_measure_us_p50(40);
    s.set_measure_us_max(80);
    s.set_camera_restarts(1);
    out.push_back(e);
  }
  {
    v1::Envelope e;
    e.mutable_heartbeat()->set_time_ns(1'700'000'000'000'000'000);
    e.mutable_heartbeat()->set_sender("hand_node");
    out.push_back(e);
  }
  {
    v1::Envelope e;
    control::Event ev;
    ev.kind = control::EventKind::kCapTight;
    ev.cycle = 3;
    ev.fingertip = 0;
    ev.has_element = true;
    ev.element_id = 12;
    ev.value = 0.006;
    ev.text = "slips in two cycles";
    wire::Answers a;
    a.add({0, 41, 1'700'000'000'000'000'000});
    wire::fill_event(ev, 1'700'000'000'000'000'000, a, fuzz::kFingertipIds, *e.mutable_event());
    out.push_back(e);
  }
  {
    v1::Envelope e;
    v1::GroundTruth& g = *e.mutable_ground_truth();
    g.set_time_ns(1'700'000'000'000'000'000);
    g.set_sim_time_s(3.5);
    g.set_cap_angle_deg(120);
    v1::FingertipTruth& t = *g.add_fingertips();
    t.set_sensor_id("left");
    t.set_camera_frame_id(7);
    out.push_back(e);
  }
  return out;
}

const char* kSensorConfigs[] = {
    "format: tactile-sensor/1\n"
    "cameras:\n"
    "  - {sensor_id: left, camera: 127.0.0.2, calibration: left.yaml}\n",

    "format: tactile-sensor/1\n"
    "publish: tcp://*:5555\n"
    "stats_period_s: 1.0\n"
    "measurement:\n"
    "  estimator: gaussian\n"
    "  reference_frames: 16\n"
    "  reference_spot_check: true\n"
    "  max_gap_frames: 1\n"
    "cameras:\n"
    "  - sensor_id: left\n"
    "    camera: 127.0.0.2\n"
    "    calibration: left.yaml\n"
    "    reference: \"\"\n"
    "    reference_cache: state/left-reference.pgm\n"
    "    fps: 100\n"
    "    packet_size: 65000\n"
    "    socket_buffer_bytes: 4194304\n"
    "    buffers: 6\n"
    "    interface: \"\"\n"
    "    packet_resend: false\n"
    "    frame_timeout_s: 0.5\n"
    "    retry_initial_s: 0.2\n"
    "    retry_max_s: 5.0\n"
    "  - sensor_id: right\n"
    "    camera: Aravis-Fake-GV02\n"
    "    calibration: right.yaml\n"
    "    fps: 50\n",
};

const char* kHandConfigs[] = {
    "format: tactile-hand/1\n"
    "fingertips:\n"
    "  - {sensor_id: left, calibration: left.yaml}\n"
    "  - {sensor_id: right, calibration: right.yaml}\n",

    "format: tactile-hand/1\n"
    "fingertips:\n"
    "  - {sensor_id: left, calibration: left.yaml}\n"
    "  - {sensor_id: right, calibration: right.yaml}\n"
    "subscribe: [tcp://127.0.0.1:5555, ipc:///tmp/frames]\n"
    "arm: tcp://127.0.0.1:5556\n"
    "events: tcp://*:5558\n"
    "heartbeat_period_s: 0.1\n"
    "control_period_s: 0.005\n"
    "pair_window_s: 0.002\n"
    "arm_timeout_s: 1.0\n"
    "controller:\n"
    "  stale_after_s: 0.03\n"
    "  dr_mm: 0.004\n"
    "  twist_dr_factor: 1.3\n"
    "  f1_n: 0.2\n"
    "  f2_n: 2.5\n"
    "  cap_x_m: 0.35\n",
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  const fs::path root = argv[1];
  try {
    Corpus envelopes(root, "envelope");
    Corpus frames(root, "tactile_frame");
    Corpus commands(root, "arm_command");
    Corpus states(root, "arm_state");
    std::string bytes;
    for (const auto& f : tactile_frames()) {
      frames.add(serialized(f));
      v1::Envelope e;
      *e.mutable_tactile_frame() = f;
      wire::encode(e, bytes);
      envelopes.add(bytes);
    }
    for (const auto& c : arm_commands()) {
      commands.add(serialized(c));
      v1::Envelope e;
      *e.mutable_arm_command() = c;
      wire::encode(e, bytes);
      envelopes.add(bytes);
    }
    for (const auto& s : arm_states()) {
      states.add(serialized(s));
      v1::Envelope e;
      *e.mutable_arm_state() = s;
      wire::encode(e, bytes);
      envelopes.add(bytes);
    }
    for (auto& e : other_envelopes()) {
      wire::encode(e, bytes);
      envelopes.add(bytes);
    }
    Corpus sensor(root, "sensor_config");
    for (const char* text : kSensorConfigs)
      sensor.add(text);
    Corpus hand(root, "hand_config");
    for (const char* text : kHandConfigs)
      hand.add(text);
    // A libFuzzer dictionary of the configuration keys (-dict=config.dict): the controller's
    // keys are many, and a mutation seldom spells one.
    std::ofstream dict(root / "config.dict");
    std::vector<std::string> keys = config::controller_config_keys();
    for (const char* k : {"format",
                          "tactile-sensor/1",
                          "tactile-hand/1",
                          "publish",
                          "stats_period_s",
                          "measurement",
                          "estimator",
                          "reference_frames",
                          "reference_spot_check",
                          "max_gap_frames",
                          "cameras",
                          "sensor_id",
                          "camera",
                          "calibration",
                          "reference",
                          "reference_cache",
                          "fps",
                          "packet_size",
                          "socket_buffer_bytes",
                          "buffers",
                          "interface",
                          "packet_resend",
                          "frame_timeout_s",
                          "retry_initial_s",
                          "retry_max_s",
                          "security",
                          "secret_key",
                          "sensor_public_key",
                          "arm_public_key",
                          "fingertips",
                          "subscribe",
                          "arm",
                          "events",
                          "heartbeat_period_s",
                          "control_period_s",
                          "pair_window_s",
                          "arm_timeout_s",
                          "arm_lost_s",
                          "controller",
                          "left.yaml",
                          "right.yaml",
                          "plain",
                          "thresholded",
                          "windowed",
                          "gaussian",
                          ".nan",
                          ".inf",
                          "~"}) {
      keys.emplace_back(k);
    }
    for (const auto& k : keys)
      dict << '"' << k << "\"\n";
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tactile_fuzz_wire_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
