#pragma once

// The known recording of the tools' tests (tactile_plot, tactile_live, tactile_web), written with
// the recorder's own LogWriter.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "tactile/recording/log_writer.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile::tools_test {

// A TactileFrame of 41 elements: elements 0..10 in contact, F_z rising with k (modulo 60), shear
// growing with k, element 4 slipping on every 10th frame (up before frame 50, down from it).
inline void fill_frame(v1::TactileFrame& f, const std::string& id, std::uint64_t k,
                       std::int64_t now) {
  f.Clear();
  f.set_sensor_id(id);
  f.set_sequence(k);
  f.set_status(v1::FRAME_STATUS_COMPLETE);
  f.set_camera_timestamp_ns(now - 2'000'000);
  f.set_receive_timestamp_ns(now - 1'500'000);
  f.set_publish_timestamp_ns(now - 1'000'000);
  for (std::uint32_t e = 0; e < 41; ++e) {
    auto* r = f.add_elements();
    r->set_id(e);
    r->set_g(100);
    if (e > 10) continue;
    const double a = 2 * 3.14159 * e / 11;
    r->set_contact(true);
    r->set_g(3000 + 100.0 * e);
    r->set_x_mm(5 + 2 * std::cos(a));
    r->set_y_mm(5 + 2 * std::sin(a));
    r->set_ux_mm(0.0005 * static_cast<double>(k) * std::cos(a));
    r->set_uy_mm(0.0003 * static_cast<double>(k));
    r->set_fx_n(0.01 * static_cast<double>(k));
    r->set_fy_n(-0.004 * static_cast<double>(k) + 0.001 * e);
    r->set_fz_n(0.05 * static_cast<double>(k % 60) + 0.02 * e);
    r->set_has_displacement(k > 0);
    if (e == 4 && k % 10 == 0) r->set_dy_mm(k < 50 ? 0.008 : -0.008);
  }
}

// A log of 100 frames of "left" and "right" 10 ms apart (sequence k at 10 k ms + 0.5 ms from the
// first record), with ground truth when asked, and hand_node's events at frames 3 (grasping
// ended, phase GRASP), 28, 53 (re-compress, TRANSPORT) and 78 (re-compress, LOWER). With
// `with_decisions`, hand_node's Decision on each pair of frames 0.1 ms after them (detector
// "learned"), which disagrees with the paper's rule: no slip on frames where element 4 moves
// beyond dr, and SLIP with element 7 marked on every frame 10 j + 5, where nothing moves.
inline void write_test_log(const std::filesystem::path& path, bool with_truth,
                           bool with_frames = true, bool with_decisions = false) {
  recording::LogWriter w(path, v1::LogHeader{}, {});
  v1::Envelope env;
  std::string buf;
  const std::int64_t t0 = 1'763'700'000'000'000'000;
  for (std::uint64_t k = 0; k < 100; ++k) {
    const std::int64_t t = t0 + static_cast<std::int64_t>(k) * 10'000'000;
    if (with_truth && k % 2 == 0) {
      auto* g = env.mutable_ground_truth();
      g->Clear();
      g->mutable_object_position_m()->set_x(0.300 + 0.0005 * static_cast<double>(k));
      wire::encode(env, buf);
      ASSERT_EQ(w.append(t, wire::kTruthTopic, "tcp://rig", v1::PAYLOAD_KIND_ENVELOPE,
                         wire::bytes_of(buf)),
                recording::WriteStatus::kOk);
    }
    for (const char* id : {"left", "right"}) {
      if (!with_frames) break;
      fill_frame(*env.mutable_tactile_frame(), id, k, t);
      wire::encode(env, buf);
      ASSERT_EQ(w.append(t + 500'000, wire::frame_topic(id), "tcp://sensor",
                         v1::PAYLOAD_KIND_ENVELOPE, wire::bytes_of(buf)),
                recording::WriteStatus::kOk);
    }
    if (with_decisions) {
      auto* d = env.mutable_decision();
      d->Clear();
      d->set_time_ns(t + 600'000);
      d->set_slip_detector("learned");
      for (const char* id : {"left", "right"}) {
        auto* a = d->add_answers();
        a->set_sensor_id(id);
        a->set_sequence(k);
        auto* tip = d->add_fingertips();
        tip->set_sensor_id(id);
        const bool slip = std::string(id) == "left" && k % 10 == 5;
        tip->set_touch(true);
        tip->set_slip(slip);
        if (slip) {
          tip->set_slipping_elements(1);
          tip->add_slipping_element_ids(7);
        }
      }
      wire::encode(env, buf);
      ASSERT_EQ(w.append(t + 600'000, wire::kDecisionTopic, "tcp://hand", v1::PAYLOAD_KIND_ENVELOPE,
                         wire::bytes_of(buf)),
                recording::WriteStatus::kOk);
    }
    if (k % 25 == 3) {
      auto* e = env.mutable_event();
      e->Clear();
      e->set_time_ns(t);
      e->set_kind(k == 3 ? v1::EVENT_KIND_GRASPING_ENDED : v1::EVENT_KIND_RECOMPRESS);
      e->set_phase(k < 25 ? "GRASP" : (k < 75 ? "TRANSPORT" : "LOWER"));
      if (k != 3) {
        e->set_sensor_id("left");
        e->set_element_id(4);
        e->set_text("re-compress");
      }
      wire::encode(env, buf);
      ASSERT_EQ(w.append(t, wire::kEventTopic, "tcp://hand", v1::PAYLOAD_KIND_ENVELOPE,
                         wire::bytes_of(buf)),
                recording::WriteStatus::kOk);
    }
  }
}

}  // namespace tactile::tools_test
