// The remeasure check on records built here: identical runs pass, a changed value is found at its
// frame and field, and what cannot be checked is counted, whatever the order of the records.
#include "remeasure.hpp"

#include <gtest/gtest.h>

#include "synthetic.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/raw_frame.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::replay {
namespace {

struct RecordedRun {
  Calibration cal;
  v1::LogRecord reference;
  std::vector<v1::LogRecord> frames;  // TactileFrame envelopes
  std::vector<v1::LogRecord> raws;    // their raw frames
};

v1::LogRecord record(const std::string& topic, v1::PayloadKind kind, std::string payload) {
  v1::LogRecord r;
  r.set_topic(topic);
  r.set_kind(kind);
  r.set_payload(std::move(payload));
  return r;
}

RecordedRun make_run(int n) {
  RecordedRun run;
  testing::SceneOptions so;
  so.width = 120;
  so.height = 80;
  run.cal = testing::grid_calibration(so, 3, 2, 30, 11);
  run.cal.sensor_id = "left";
  ExtractorOptions xo;
  xo.reference_frames = 1;
  Extractor x(run.cal, xo);
  util::Random rng(5);
  testing::SceneRenderer renderer(so, &run.cal);
  Image img;
  renderer.render({}, rng, img);
  x.add_reference_frame(img.view());
  v1::RawFrame raw;
  raw.set_sensor_id("left");
  raw.set_kind(v1::RAW_FRAME_KIND_REFERENCE);
  wire::fill_raw_pixels(img.view(), raw);
  wire::fill_settings(xo, *raw.mutable_settings());
  run.reference =
      record(wire::raw_topic("left"), v1::PAYLOAD_KIND_RAW_FRAME, raw.SerializeAsString());
  v1::Envelope env;
  std::string buf;
  for (int k = 0; k < n; ++k) {
    std::vector<testing::Spot> spots;
    for (const auto& e : run.cal.elements) {
      testing::Spot s;
      s.center = {e.center_px.x + 0.1 * k, e.center_px.y};
      s.peak = 60;
      spots.push_back(s);
    }
    renderer.render(spots, rng, img);
    x.measure(img.view(), {static_cast<std::uint64_t>(k), k * 10'000'000LL});
    wire::FrameHeader h;
    h.sequence = static_cast<std::uint64_t>(k);
    h.status = v1::FRAME_STATUS_COMPLETE;
    wire::fill_tactile_frame("left", h, x.readings(), run.cal.mm_per_px,
                             *env.mutable_tactile_frame());
    wire::encode(env, buf);
    run.frames.push_back(record(wire::frame_topic("left"), v1::PAYLOAD_KIND_ENVELOPE, buf));
    raw.Clear();
    raw.set_sensor_id("left");
    raw.set_kind(v1::RAW_FRAME_KIND_MEASURED);
    raw.set_tactile_sequence(h.sequence);
    raw.set_sequence(static_cast<std::uint64_t>(k));
    raw.set_camera_timestamp_ns(k * 10'000'000LL);
    wire::fill_raw_pixels(img.view(), raw);
    run.raws.push_back(
        record(wire::raw_topic("left"), v1::PAYLOAD_KIND_RAW_FRAME, raw.SerializeAsString()));
  }
  return run;
}

TEST(Remeasure, IdenticalInEitherOrderOfFrameAndRawFrame) {
  const RecordedRun run = make_run(12);
  Remeasurer rm({run.cal});
  rm.add(run.reference);
  for (std::size_t k = 0; k < run.frames.size(); ++k) {
    if (k % 2 == 0) {
      rm.add(run.frames[k]);
      rm.add(run.raws[k]);
    } else {
      rm.add(run.raws[k]);
      rm.add(run.frames[k]);
    }
    rm.add(run.reference);  // republished: no effect
  }
  rm.finish();
  ASSERT_EQ(rm.reports().size(), 1U);
  EXPECT_EQ(rm.reports()[0].checked, 12U);
  EXPECT_EQ(rm.reports()[0].identical, 12U);
  EXPECT_EQ(rm.reports()[0].references, 1U);
  EXPECT_TRUE(rm.all_identical());
  EXPECT_FALSE(rm.first_difference());
}

TEST(Remeasure, AChangedValueIsFoundAtItsFrameAndField) {
  RecordedRun run = make_run(8);
  // Change element 2's F_z in frame 5 by one bit.
  v1::Envelope env;
  ASSERT_TRUE(env.ParseFromString(run.frames[5].payload()));
  auto* e = env.mutable_tactile_frame()->mutable_elements(2);
  ASSERT_TRUE(e->contact());
  e->set_fz_n(std::nextafter(e->fz_n(), 10.0));
  run.frames[5].set_payload(env.SerializeAsString());
  Remeasurer rm({run.cal});
  rm.add(run.reference);
  for (std::size_t k = 0; k < run.frames.size(); ++k) {
    rm.add(run.frames[k]);
    rm.add(run.raws[k]);
  }
  rm.finish();
  EXPECT_FALSE(rm.all_identical());
  EXPECT_EQ(rm.differing(), 1U);
  ASSERT_TRUE(rm.first_difference());
  EXPECT_EQ(rm.first_difference()->sequence, 5U);
  EXPECT_NE(rm.first_difference()->what.find("element 2 (id 2) fz_n: recorded "), std::string::npos)
      << rm.first_difference()->what;
  EXPECT_EQ(rm.reports()[0].identical, 7U);
}

TEST(Remeasure, WhatCannotBeCheckedIsCounted) {
  const RecordedRun run = make_run(10);
  Remeasurer rm({});  // no calibration: the sensor is named, nothing checked
  for (const auto& f : run.frames)
    rm.add(f);
  rm.finish();
  ASSERT_EQ(rm.uncalibrated().size(), 1U);
  EXPECT_EQ(rm.uncalibrated()[0], "left");
  EXPECT_FALSE(rm.all_identical());

  Remeasurer r2({run.cal});
  r2.add(run.frames[0]);
  r2.add(run.raws[0]);  // before any reference
  r2.add(run.reference);
  for (std::size_t k = 1; k < run.frames.size(); ++k) {
    r2.add(run.frames[k]);
    if (k != 4) r2.add(run.raws[k]);  // frame 4's raw frame is lost
  }
  r2.finish();
  const SensorReport& rep = r2.reports()[0];
  EXPECT_EQ(rep.no_reference, 1U);
  // Frames 1 and 5 follow frames the core did not see (0 came before the reference, 4's raw
  // frame is lost): their displacement cannot be reproduced, and the check says so.
  EXPECT_EQ(rep.unchecked, 2U);  // frames 0 and 4
  EXPECT_EQ(rep.checked, 8U);
  EXPECT_EQ(rep.identical, 6U);
  ASSERT_TRUE(r2.first_difference());
  EXPECT_EQ(r2.first_difference()->sequence, 1U);
  EXPECT_NE(r2.first_difference()->what.find("has_displacement: recorded true, remeasured false"),
            std::string::npos)
      << r2.first_difference()->what;
}

}  // namespace
}  // namespace tactile::replay
