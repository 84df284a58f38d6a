// tactile_record, tactile_replay and tactile_plot on the real sensor_node, which measures the
// frames of Aravis's own fake GigE Vision camera (arv-fake-gv-camera-0.8) in a private network
// namespace (this executable's main enters it).
#include <gtest/gtest.h>
#include <signal.h>

#include "process.hpp"
#include "support/child_process.hpp"
#include "synthetic.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/pgm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "tools_support.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using camera::testing::ChildProcess;
using testing::Process;
using testing::TempDir;
using tools_test::await_match;
using tools_test::read_log;

TEST(SensorNodeRecording, RecordsReplaysAndPlotsARealSensorNode) {
  TempDir dir;
  testing::SceneOptions o;  // 640 x 480, 8 bits
  Calibration cal = testing::grid_calibration(o, 8, 5, 60, 14);
  cal.sensor_id = "left";
  config::save_calibration(dir / "left.yaml", cal);
  Image zero(o.width, o.height, PixelFormat::kMono8);
  util::write_pgm(dir / "zero.pgm", zero.view());
  const std::string endpoint = "ipc://" + (dir / "frames").string();

  ChildProcess fake({"arv-fake-gv-camera-0.8", "-i", "127.0.0.2", "-s", "TACTILE09"});
  Process node({TACTILE_SENSOR_NODE_PATH, "--camera", "127.0.0.2", "--calibration",
                (dir / "left.yaml").string(), "--reference", (dir / "zero.pgm").string(),
                "--publish", endpoint, "--fps", "100"});
  const auto rec = testing::run({TACTILE_RECORD_PATH, "-o", (dir / "node.tlog").string(), endpoint,
                                 "--topic", "frame/", "--count", "120"},
                                60s);
  ASSERT_EQ(rec.exit_code, 0) << rec.err << node.err_so_far() << fake.output();
  EXPECT_NE(rec.err.find("recorded 120 messages"), std::string::npos) << rec.err;

  const auto log = read_log(dir / "node.tlog");
  EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
  ASSERT_EQ(log.records.size(), 120U);
  v1::Envelope env;
  std::uint64_t previous = 0;
  for (std::size_t i = 0; i < log.records.size(); ++i) {
    const auto& r = log.records[i];
    EXPECT_EQ(r.topic(), "frame/left");
    EXPECT_EQ(r.source(), endpoint);
    const auto* p = reinterpret_cast<const std::uint8_t*>(r.payload().data());
    ASSERT_EQ(wire::decode({p, r.payload().size()}, env), wire::DecodeStatus::kOk);
    const v1::TactileFrame& f = env.tactile_frame();
    EXPECT_EQ(f.status(), v1::FRAME_STATUS_COMPLETE);
    EXPECT_EQ(f.elements_size(), 40);
    if (i > 0) {
      EXPECT_EQ(f.sequence(), previous + 1);  // nothing lost between node and log
    }
    previous = f.sequence();
    EXPECT_GE(r.receive_time_ns(), f.publish_timestamp_ns());
  }

  // Played back, the subscriber gets the recorded bytes.
  Process replay({TACTILE_REPLAY_PATH, (dir / "node.tlog").string(), "--publish",
                  "tcp://127.0.0.1:*", "--as-fast-as-possible", "--wait-subscriptions", "1"});
  const auto ep = await_match([&] { return replay.err_so_far(); }, "publishing on (tcp://\\S+)");
  ASSERT_TRUE(ep) << replay.err_so_far();
  zmq::context_t ctx;
  wire::Subscriber sub(ctx, {*ep}, {"frame/"});
  wire::TopicMessage m;
  std::size_t got = 0;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (got < log.records.size() && std::chrono::steady_clock::now() < deadline) {
    if (!sub.receive(m, 100ms)) continue;
    ASSERT_EQ(std::string(m.payload.begin(), m.payload.end()), log.records[got].payload());
    ++got;
  }
  EXPECT_EQ(got, log.records.size());
  EXPECT_EQ(replay.wait(20s).exit_code, 0);

  const auto plot =
      testing::run({TACTILE_PLOT_PATH, (dir / "node.tlog").string(), "-o", (dir / "plots").string(),
                    "--calibration", (dir / "left.yaml").string()},
                   60s);
  EXPECT_EQ(plot.exit_code, 0) << plot.err;
  for (const char* name :
       {"shear_left.png", "fig10.png", "forces_left.png", "timeline.png", "latency.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / "plots" / name)) << name;

  node.signal(SIGTERM);
  EXPECT_EQ(node.wait(10s).exit_code, 0);
}

}  // namespace
}  // namespace tactile
