// A stand-in for sensor_node with raw frames switched on (the change proposed in
// docs/recording.md), and for hand_node's events and the rig's ground truth: synthetic frames go
// through the real measurement core, and every frame is published as sensor_node publishes it
// (topic frame/<id>), followed by its raw frame (raw/<id>); the reference image in use goes out
// as a REFERENCE raw frame first and again every --reference-every frames.
//
//   fake_sensor --calibration CAL.yaml [--frames 40] [--raw] [--bit-depth 8] [--events]
//               [--truth] [--wait-subscriptions 1] [--seed 1]
//
// Prints "endpoints frames=EP events=EP truth=EP" on standard output once bound, then waits for
// the subscriptions, publishes, prints "done N" with the number of messages sent, and exits.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "player.hpp"
#include "synthetic.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/extractor.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/raw_frame.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace {

using namespace tactile;

struct Options {
  std::string calibration;
  int frames = 40;
  bool raw = false;
  int bit_depth = 8;
  bool events = false;
  bool truth = false;
  int wait = 1;
  int reference_every = 25;
  std::uint64_t seed = 1;
  std::string estimator = "gaussian";
};

int run(const Options& opt) {
  testing::SceneOptions so;
  so.width = 200;
  so.height = 150;
  so.bit_depth = opt.bit_depth;
  Calibration cal = testing::grid_calibration(so, 5, 3, 36, 13);
  cal.sensor_id = "left";
  config::save_calibration(opt.calibration, cal);
  ExtractorOptions xo;
  xo.estimator = *parse_estimator(opt.estimator);
  xo.reference_frames = 1;
  xo.max_gap_frames = 1;
  Extractor extractor(cal, xo);

  util::Random rng(opt.seed);
  testing::SceneRenderer renderer(so, &cal);
  Image img;
  renderer.render({}, rng, img);
  extractor.begin_reference();
  auto rr = extractor.add_reference_frame(img.view());
  if (rr.status != ReferenceStatus::kComplete) {
    std::fprintf(stderr, "fake_sensor: reference %s\n", to_string(rr.status));
    return 1;
  }
  const Image reference = img;

  zmq::context_t ctx;
  replay::PlayerOptions po;
  po.endpoint = "tcp://127.0.0.1:*";
  po.wait_subscriptions = opt.wait;
  replay::Player frames(ctx, po);
  std::unique_ptr<replay::Player> events;
  std::unique_ptr<replay::Player> truth;
  if (opt.events) events = std::make_unique<replay::Player>(ctx, po);
  if (opt.truth) truth = std::make_unique<replay::Player>(ctx, po);
  std::printf("endpoints frames=%s events=%s truth=%s\n", frames.endpoint().c_str(),
              events ? events->endpoint().c_str() : "-", truth ? truth->endpoint().c_str() : "-");
  std::fflush(stdout);
  if (!frames.wait_for_subscribers() || (events && !events->wait_for_subscribers()) ||
      (truth && !truth->wait_for_subscribers())) {
    std::fprintf(stderr, "fake_sensor: no subscribers\n");
    return 1;
  }

  v1::Envelope env;
  std::string buf;
  v1::RawFrame raw;
  std::string raw_buf;
  std::uint64_t sent = 0;
  const std::string topic = wire::frame_topic(cal.sensor_id);
  const std::string raw_topic = wire::raw_topic(cal.sensor_id);
  auto send_reference = [&] {
    raw.Clear();
    raw.set_sensor_id(cal.sensor_id);
    raw.set_kind(v1::RAW_FRAME_KIND_REFERENCE);
    wire::fill_raw_pixels(reference.view(), raw);
    wire::fill_settings(xo, *raw.mutable_settings());
    raw.SerializeToString(&raw_buf);
    frames.send(raw_topic, wire::bytes_of(raw_buf));
    ++sent;
  };
  if (opt.raw) send_reference();

  const std::int64_t period = 10'000'000;
  const std::int64_t t0 = util::realtime_ns();
  std::uint64_t camera_sequence = 0;
  for (int k = 0; k < opt.frames; ++k) {
    // Spots press in and slide; frame 17 is lost (a gap of two camera frames) and frame 30 is
    // the first after a camera restart.
    camera_sequence += k == 17 ? 2 : 1;
    const bool restart = k == 30;
    std::vector<testing::Spot> spots;
    for (std::size_t e = 0; e < cal.elements.size(); ++e) {
      if ((e + static_cast<std::size_t>(k)) % 4 == 0) continue;
      testing::Spot s;
      s.center = {
          cal.elements[e].center_px.x + 0.07 * k + 0.3 * std::sin(0.4 * k + static_cast<double>(e)),
          cal.elements[e].center_px.y - 0.05 * k};
      s.peak = 40 + 3.0 * k + 5.0 * static_cast<double>(e % 5);
      s.sigma = 2.2;
      spots.push_back(s);
    }
    renderer.render(spots, rng, img);
    if (restart) extractor.forget_previous();
    const auto ms = extractor.measure(img.view(), {camera_sequence, t0 + k * period});
    wire::FrameHeader h;
    h.sequence = static_cast<std::uint64_t>(k);
    h.camera_frame_id = camera_sequence % 65535 + 1;
    h.camera_timestamp_ns = t0 + k * period;
    h.receive_timestamp_ns = h.camera_timestamp_ns + 400'000;
    h.status = ms == MeasureStatus::kOk ? v1::FRAME_STATUS_COMPLETE : v1::FRAME_STATUS_WRONG_FORMAT;
    h.nominal_period_ns = period;
    h.frames_skipped = k == 17 ? 1 : 0;
    h.measure_time_us = 12.5;
    h.publish_timestamp_ns = util::realtime_ns();
    wire::fill_tactile_frame(cal.sensor_id, h, extractor.readings(), cal.mm_per_px,
                             *env.mutable_tactile_frame());
    wire::encode(env, buf);
    frames.send(topic, wire::bytes_of(buf));
    ++sent;
    if (opt.raw) {
      raw.Clear();
      raw.set_sensor_id(cal.sensor_id);
      raw.set_kind(v1::RAW_FRAME_KIND_MEASURED);
      raw.set_tactile_sequence(h.sequence);
      raw.set_sequence(camera_sequence);
      raw.set_camera_frame_id(h.camera_frame_id);
      raw.set_camera_timestamp_ns(h.camera_timestamp_ns);
      raw.set_receive_timestamp_ns(h.receive_timestamp_ns);
      raw.set_forget_previous(restart);
      wire::fill_raw_pixels(img.view(), raw);
      raw.SerializeToString(&raw_buf);
      frames.send(raw_topic, wire::bytes_of(raw_buf));
      ++sent;
      if ((k + 1) % opt.reference_every == 0) send_reference();
    }
    if (events && k % 10 == 5) {
      v1::Envelope ev;
      auto* e = ev.mutable_event();
      e->set_time_ns(util::realtime_ns());
      e->set_kind(k == 5 ? v1::EVENT_KIND_PHASE : v1::EVENT_KIND_RECOMPRESS);
      e->set_phase(k == 5 ? "grasp" : "transport");
      e->set_sensor_id(cal.sensor_id);
      e->set_element_id(static_cast<std::uint32_t>(k % 15));
      e->set_value(0.1 * k);
      e->set_text("event at frame " + std::to_string(k));
      wire::encode(ev, buf);
      events->send(wire::kEventTopic, wire::bytes_of(buf));
      ++sent;
    }
    if (truth && k % 5 == 0) {
      v1::Envelope gt;
      auto* g = gt.mutable_ground_truth();
      g->set_time_ns(util::realtime_ns());
      g->set_sim_time_s(0.01 * k);
      g->mutable_object_position_m()->set_x(0.30 + 0.001 * k);
      g->mutable_object_position_m()->set_z(0.05);
      g->set_cap_angle_deg(2.0 * k);
      wire::encode(gt, buf);
      truth->send(wire::kTruthTopic, wire::bytes_of(buf));
      ++sent;
    }
  }
  std::printf("done %llu\n", static_cast<unsigned long long>(sent));
  std::fflush(stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"A stand-in for sensor_node with raw frames, hand_node events and rig truth."};
  app.add_option("--calibration", opt.calibration, "calibration file to write")->required();
  app.add_option("--frames", opt.frames, "frames to publish");
  app.add_flag("--raw", opt.raw, "publish raw frames and the reference");
  app.add_option("--bit-depth", opt.bit_depth, "8 or 16");
  app.add_flag("--events", opt.events, "publish events on a second endpoint");
  app.add_flag("--truth", opt.truth, "publish ground truth on a third endpoint");
  app.add_option("--wait-subscriptions", opt.wait, "subscriptions to wait for on each endpoint");
  app.add_option("--reference-every", opt.reference_every, "republish the reference this often");
  app.add_option("--seed", opt.seed, "noise seed");
  app.add_option("--estimator", opt.estimator, "centroid estimator");
  CLI11_PARSE(app, argc, argv);
  try {
    return run(opt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fake_sensor: %s\n", e.what());
    return 1;
  }
}
