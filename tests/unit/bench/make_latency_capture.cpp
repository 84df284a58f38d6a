// Writes tests/data/latency/capture.tlog: a small capture of a pipeline run at 100 fps in the
// form the latency benchmark keeps (bench/system/latency_analysis.hpp), with latencies chosen so
// that every figure of the analysis is known by hand (latency_analysis_test.cpp says which).
//
//   make_latency_capture OUT.tlog
//
// 30 exposures k = 0..29, 10 ms apart, of two sensors:
// - left received 1.00 + 0.01 k ms after its camera timestamp, right 1.5 ms; published 0.3 ms
//   after (0.2 ms of it the measurement core), received by hand_node 0.1 ms after that, and by the
//   benchmark's subscriber 0.05 ms after publishing;
// - right's frame of k = 12 never reaches the subscriber (a sequence gap), left's of k = 20 misses
//   packets;
// - every other exposure is answered by a command 0.04 ms after hand_node received its later
//   frame (a hold at k = 22, move_to otherwise), and its Decision 0.01 ms before the command;
// - left truly slides at k = 15..17 (one episode) and hand_node re-compresses on k = 16's frames.
#include <cstdio>
#include <string>
#include <vector>

#include "latency_analysis.hpp"
#include "tactile/wire/envelope.hpp"

namespace {

using tactile::bench::Captured;
namespace v1 = tactile::v1;
namespace wire = tactile::wire;

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;
constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kUs = 1'000;

std::int64_t camera_ns(int k) {
  return kT0 + k * 10 * kMs;
}
std::int64_t receive_ns(int k, bool left) {
  return camera_ns(k) + (left ? kMs + 10 * kUs * k : 1500 * kUs);
}
std::int64_t publish_ns(int k, bool left) {
  return receive_ns(k, left) + 300 * kUs;
}
std::int64_t hand_receive_ns(int k, bool left) {
  return publish_ns(k, left) + 100 * kUs;
}
std::int64_t send_ns(int k) {
  return hand_receive_ns(k, false) + 40 * kUs;  // right is always the later one
}

void add(std::vector<Captured>& cap, std::int64_t at_ns, const std::string& topic,
         v1::Envelope& env) {
  std::string bytes;
  wire::encode(env, bytes);
  cap.push_back({at_ns, topic, std::vector<std::uint8_t>(bytes.begin(), bytes.end())});
}

void add_ref(google::protobuf::RepeatedPtrField<v1::FrameRef>* refs, int k) {
  for (const bool left : {true, false}) {
    v1::FrameRef* ref = refs->Add();
    ref->set_sensor_id(left ? "left" : "right");
    ref->set_sequence(static_cast<std::uint64_t>(k + 1));
    ref->set_camera_timestamp_ns(camera_ns(k));
    ref->set_receive_timestamp_ns(hand_receive_ns(k, left));
  }
}

std::vector<Captured> capture() {
  std::vector<Captured> cap;
  for (int k = 0; k < 30; ++k) {
    v1::Envelope truth;
    truth.mutable_ground_truth()->set_time_ns(camera_ns(k));
    for (const bool left : {true, false}) {
      v1::FingertipTruth* tip = truth.mutable_ground_truth()->add_fingertips();
      tip->set_sensor_id(left ? "left" : "right");
      tip->set_camera_timestamp_ns(camera_ns(k));
      tip->add_elements()->set_sliding(left && k >= 15 && k <= 17);
    }
    add(cap, camera_ns(k) + 100 * kUs, wire::kTruthTopic, truth);
    for (const bool left : {true, false}) {
      if (!left && k == 12) continue;
      v1::Envelope env;
      v1::TactileFrame& f = *env.mutable_tactile_frame();
      f.set_sensor_id(left ? "left" : "right");
      f.set_sequence(static_cast<std::uint64_t>(k + 1));
      f.set_status(left && k == 20 ? v1::FRAME_STATUS_MISSING_PACKETS : v1::FRAME_STATUS_COMPLETE);
      f.set_camera_timestamp_ns(camera_ns(k));
      f.set_receive_timestamp_ns(receive_ns(k, left));
      f.set_publish_timestamp_ns(publish_ns(k, left));
      f.set_measure_time_us(200);
      add(cap, publish_ns(k, left) + 50 * kUs, wire::frame_topic(f.sensor_id()), env);
    }
    if (k == 12 || k == 20) continue;
    v1::Envelope decision;
    decision.mutable_decision()->set_time_ns(send_ns(k) - 10 * kUs);
    add_ref(decision.mutable_decision()->mutable_answers(), k);
    add(cap, send_ns(k) + 20 * kUs, wire::kDecisionTopic, decision);
    v1::Envelope command;
    v1::ArmCommand& c = *command.mutable_arm_command();
    c.set_sequence(static_cast<std::uint64_t>(k + 1));
    c.set_send_timestamp_ns(send_ns(k));
    if (k == 22) {
      c.mutable_hold();
    } else {
      c.mutable_move_to();
    }
    add_ref(c.mutable_answers(), k);
    add(cap, send_ns(k) + 30 * kUs, wire::kCommandTopic, command);
    if (k == 16) {
      v1::Envelope event;
      v1::Event& e = *event.mutable_event();
      e.set_time_ns(send_ns(k) + 5 * kUs);
      e.set_kind(v1::EVENT_KIND_RECOMPRESS);
      e.set_sensor_id("left");
      add_ref(e.mutable_answers(), k);
      add(cap, send_ns(k) + 40 * kUs, wire::kEventTopic, event);
    }
  }
  return cap;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || std::string(argv[1]) == "--help") {
    std::fprintf(argc == 2 ? stdout : stderr, "usage: make_latency_capture OUT.tlog\n");
    return argc == 2 ? 0 : 2;
  }
  try {
    tactile::bench::write_capture(argv[1], capture(), "synthetic: make_latency_capture");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_latency_capture: %s\n", e.what());
    return 1;
  }
  return 0;
}
