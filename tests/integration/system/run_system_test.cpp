// scripts/run-system as a user runs it, as root: the nodes' endpoints reachable from the host at
// the addresses it prints (a veth pair into its private network namespace, removed at the end),
// a recorder on the host hears frames, events and ground truth there, and --record --raw-frames
// leaves a whole log that tactile_replay --remeasure checks bit for bit. Not as root, the nodes'
// ipc:// endpoints reachable from the host; --host-net none, nothing joined to the host.
#include <gtest/gtest.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <map>
#include <regex>

#include "process.hpp"
#include "tactile/util/files.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "tools_support.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using testing::Process;
using testing::TempDir;
using tools_test::await_match;
using tools_test::read_log;

const std::filesystem::path kSource = TACTILE_SOURCE_DIR;

// Another network than the default, so the test runs beside a run-system of the user's.
constexpr const char* kHostNet = "10.77.19.0/30";
constexpr const char* kNamespaceAddress = "10.77.19.2";

TEST(RunSystem, EndpointsReachableFromTheHostAndTheRunRecordedWithRawFrames) {
  ASSERT_EQ(::geteuid(), 0U) << "a veth pair into the host needs root (CI runs as root)";
  TempDir dir;
  const auto inside = dir / "inside.tlog";
  const std::filesystem::path host = TACTILE_FIRST_HOUR_LOG;
  std::filesystem::create_directories(host.parent_path());
  Process run({"bash", (kSource / "scripts/run-system").string(), "--build", TACTILE_BUILD_DIR,
               "--scenario", TACTILE_OBSERVE_SCENARIO, "--out", (dir / "out").string(), "--record",
               inside.string(), "--raw-frames", "--host-net", kHostNet});
  const auto line = await_match([&] { return run.err_so_far(); },
                                "run-system: endpoints: frames (\\S+) events (\\S+) truth (\\S+)");
  ASSERT_TRUE(line) << run.err_so_far();
  // The documented addresses (docs/system.md): the namespace's end of the veth pair.
  const std::string ns = std::string("tcp://") + kNamespaceAddress;
  std::smatch m;
  const std::string err = run.err_so_far();
  ASSERT_TRUE(std::regex_search(
      err, m,
      std::regex("endpoints: frames (\\S+) events (\\S+) truth (\\S+) \\(the host is "
                 "10\\.77\\.19\\.1\\)")))
      << err;
  EXPECT_EQ(m[1], ns + ":5555");
  EXPECT_EQ(m[2], ns + ":5558");
  EXPECT_EQ(m[3], ns + ":5557");
  // The command it prints for recording from the host, with our file.
  EXPECT_NE(err.find("record from the host: " + std::string(TACTILE_BUILD_DIR) +
                     "/tools/tactile_record/tactile_record -o run.tlog " + m[1].str() + " " +
                     m[2].str() + " " + m[3].str()),
            std::string::npos)
      << err;
  // 10 s from the host with the printed command, as the README says; the recording is the
  // first_hour fixture's, which the next steps read in Python, export to MCAP and plot.
  std::filesystem::remove(host);
  Process recorder(
      {TACTILE_RECORD_PATH, "-o", host.string(), "--duration", "10", m[1], m[2], m[3]});

  // observe.yaml ends at its max_time_s with the task unfinished: exit 1, saying so.
  const auto r = run.wait(180s);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("the task did not complete"), std::string::npos) << r.err;
  EXPECT_TRUE(std::regex_search(r.err, std::regex("run-system: recorded \\d+ messages"))) << r.err;
  // hand_node's first line on the console: the detector (the control core's default here) and
  // the grip it runs.
  EXPECT_NE(r.err.find("info: slip detector: learned, grip: paper\n"), std::string::npos) << r.err;
  // The paths it prints open from where it was run: absolute, not relative to its output folder.
  const std::string out = (dir / "out").string();
  EXPECT_NE(r.err.find("run-system: report " + out + "/report.json; plots: " + out + "/fig10.png " +
                       out + "/"),
            std::string::npos)
      << r.err;
  // The latency beside the machine's steal and load (docs/rig.md, "The machine's load").
  EXPECT_TRUE(std::regex_search(
      r.err, std::regex("run-system: latency p50 [0-9.]+ ms, p99 [0-9.]+ ms, max [0-9.]+ ms; "
                        "machine: CPU steal [0-9.]+ %, load average [0-9.]+ on [0-9]+ cores\n")))
      << r.err;
  const auto rec = recorder.wait(30s);
  EXPECT_FALSE(rec.timed_out);
  EXPECT_EQ(rec.exit_code, 0) << rec.err;

  // Nothing left behind on the host: the veth pair is gone.
  const auto links = testing::run({"ip", "-o", "link", "show"});
  EXPECT_EQ(links.out.find("tsys" + std::to_string(run.pid()) + "@"), std::string::npos)
      << links.out;

  // From the host: frames of both fingertips, events and truth, each from its endpoint.
  const auto from_host = read_log(host);
  EXPECT_EQ(from_host.end, recording::ReadStatus::kEnd);
  const auto count = [](const tools_test::LogContents& c, const std::string& topic) {
    const auto it = c.per_topic.find(topic);
    return it == c.per_topic.end() ? 0 : it->second;
  };
  // 8 s of frames at 30 fps or more; the grasp's events.
  for (const std::string topic : {"frame/left", "frame/right", "truth"})
    EXPECT_GT(count(from_host, topic), 50) << topic;
  EXPECT_GE(count(from_host, "event"), 3);
  for (const auto& record : from_host.records) {
    const std::string& t = record.topic();
    const std::string expected = t.starts_with("frame/") || t.starts_with("stats/") ? m[1]
                                 : t == "truth"                                     ? m[3]
                                                                                    : m[2];
    ASSERT_EQ(record.source(), expected) << t;
  }

  // run-system's own recording: whole, every topic, raw frames too, ...
  const auto log = read_log(inside);
  EXPECT_EQ(log.end, recording::ReadStatus::kEnd);
  for (const std::string topic : {"frame/left", "frame/right", "raw/left", "raw/right",
                                  "stats/left", "event", "arm", "command", "decision", "truth"})
    EXPECT_GT(count(log, topic), 0) << topic;
  // ... which the measurement core measures again bit for bit.
  const auto config = dir / "out/config";
  const auto remeasure =
      testing::run({TACTILE_REPLAY_PATH, inside.string(), "--remeasure",
                    (config / "left.yaml").string(), (config / "right.yaml").string()},
                   120s);
  EXPECT_EQ(remeasure.exit_code, 0) << remeasure.out << remeasure.err;
  EXPECT_TRUE(
      std::regex_search(remeasure.out + remeasure.err,
                        std::regex("left: \\d+ frames measured again, \\d+ identical bit for "
                                   "bit, 0 differ")))
      << remeasure.out << remeasure.err;
}

// Not as root (here the user nobody), the nodes run in a user namespace that no veth pair joins to
// the host; they also bind ipc:// endpoints in OUT/ipc, which run-system prints, and a subscriber
// on the host receives each publisher's messages there (docs/system.md, "Not as root").
TEST(RunSystem, NotAsRootTheNodesIpcEndpointsReachTheHost) {
  ASSERT_EQ(::geteuid(), 0U) << "the test becomes nobody with setpriv (CI runs as root)";
  const passwd* nobody = ::getpwnam("nobody");
  ASSERT_NE(nobody, nullptr);
  TempDir dir;
  // nobody writes the run's output folder (run-system removes and makes OUT, so its parent).
  const auto parent = dir / "nobody";
  std::filesystem::create_directories(parent);
  std::filesystem::permissions(
      dir.path(), std::filesystem::perms::owner_all | std::filesystem::perms::others_exec);
  ASSERT_EQ(::chown(parent.c_str(), nobody->pw_uid, nobody->pw_gid), 0);
  const auto out = parent / "out";
  // Where the checkout is out of nobody's reach (a workspace under a home of mode 700), the run
  // sees the source and the build through bind mounts at reachable paths, in a mount namespace of
  // its own: nothing changes on the machine.
  std::filesystem::path source = kSource, build = TACTILE_BUILD_DIR;
  std::vector<std::string> argv;
  const bool reachable =
      tactile::testing::run({"setpriv", "--reuid=nobody", "--regid=nogroup", "--clear-groups",
                             "test", "-r", (kSource / "scripts/run-system").string(), "-a", "-x",
                             (build / "rig/rig").string()})
          .exit_code == 0;
  if (!reachable) {
    source = dir / "source";
    build = dir / "build";
    std::filesystem::create_directories(source);
    std::filesystem::create_directories(build);
    argv = {"unshare",
            "--mount",
            "--propagation",
            "private",
            "sh",
            "-c",
            "mount --bind \"$1\" \"$2\" && mount --bind \"$3\" \"$4\" && shift 4 && exec \"$@\"",
            "sh",
            kSource.string(),
            source.string(),
            TACTILE_BUILD_DIR,
            build.string()};
  }
  for (const std::string& a :
       {std::string("setpriv"), std::string("--reuid=nobody"), std::string("--regid=nogroup"),
        std::string("--clear-groups"), std::string("bash"),
        (source / "scripts/run-system").string(), std::string("--build"), build.string(),
        std::string("--scenario"),
        (source / std::filesystem::path(TACTILE_OBSERVE_SCENARIO).lexically_relative(kSource))
            .string(),
        std::string("--out"), out.string(), std::string("--camera-link"), std::string("loopback")})
    argv.push_back(a);
  Process run(argv);
  ASSERT_TRUE(await_match([&] { return run.err_so_far(); },
                          "run-system: endpoints: frames (\\S+) events (\\S+) truth (\\S+)"))
      << run.err_so_far();
  const std::string err = run.err_so_far();
  EXPECT_NE(err.find("run-system: not root: "), std::string::npos) << err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      err, m,
      std::regex("endpoints: frames (\\S+) events (\\S+) truth (\\S+) \\(from the host, "
                 "through the file system\\)")))
      << err;
  const std::string ipc = "ipc://" + (out / "ipc").string();
  EXPECT_EQ(m[1], ipc + "/sensor.ipc");
  EXPECT_EQ(m[2], ipc + "/events.ipc");
  EXPECT_EQ(m[3], ipc + "/truth.ipc");
  EXPECT_NE(err.find("record from the host: " + build.string() +
                     "/tools/tactile_record/tactile_record -o run.tlog " + m[1].str() + " " +
                     m[2].str() + " " + m[3].str()),
            std::string::npos)
      << err;

  // From the host, outside the namespace: a subscriber on each printed endpoint, for 2 s from the
  // first frame (the nodes start after the line; a subscriber may connect before its publisher
  // binds).
  zmq::context_t ctx;
  const std::vector<std::string> endpoints{m[1], m[2], m[3]};
  std::vector<std::unique_ptr<wire::Subscriber>> subscribers;
  for (const auto& e : endpoints)
    subscribers.push_back(std::make_unique<wire::Subscriber>(ctx, std::vector<std::string>{e},
                                                             std::vector<std::string>{""}));
  std::vector<std::map<std::string, int>> topics(endpoints.size());
  wire::TopicMessage message;
  auto until = std::chrono::steady_clock::now() + 30s;
  bool first = true;
  while (std::chrono::steady_clock::now() < until) {
    for (std::size_t i = 0; i < subscribers.size(); ++i) {
      while (subscribers[i]->receive(message, 1ms)) {
        ++topics[i][message.topic];
        if (first && i == 0) until = std::chrono::steady_clock::now() + 2s;
        first = first && i != 0;
      }
    }
  }
  // 2 s at 100 fps (30 under the sanitizers: 26 decisions were seen there), frames of both
  // fingertips; hand_node's steps; the truth of each frame: each publisher reaches the host.
  EXPECT_GT(topics[0]["frame/left"], 10);
  EXPECT_GT(topics[0]["frame/right"], 10);
  EXPECT_GT(topics[1]["decision"], 10);
  EXPECT_GT(topics[1]["arm"], 10);
  EXPECT_GT(topics[2]["truth"], 10);
  // The sockets are the unprivileged user's (the nodes ran as nobody, mapped to root inside).
  struct stat socket_stat {};
  ASSERT_EQ(::stat((out / "ipc/sensor.ipc").c_str(), &socket_stat), 0);
  EXPECT_TRUE(S_ISSOCK(socket_stat.st_mode));
  EXPECT_EQ(socket_stat.st_uid, nobody->pw_uid);

  // observe.yaml ends at its max_time_s with the task unfinished: exit 1, saying so.
  const auto r = run.wait(60s);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("the task did not complete"), std::string::npos) << r.err;
}

// The cameras behind one link shaped to 1 Gbit/s at MTU 1500 (docs/system.md, "Camera links"):
// the rig serves them in a namespace of their own, sensor_node receives their region of interest
// over the link, and the task completes with every frame whole. With --host-net none as root, in
// a namespace of its own that nothing joins to the host: no veth pair, no ipc endpoints, and it
// says that the endpoints are not reachable from the host.
TEST(RunSystem, CamerasBehindOneLinkShapedToLineRateCompleteTheTask) {
  ASSERT_EQ(::geteuid(), 0U) << "--host-net none is root's (CI runs as root)";
  TempDir dir;
  const auto out = dir / "out";
  Process run({"bash", (kSource / "scripts/run-system").string(), "--build", TACTILE_BUILD_DIR,
               "--scenario", TACTILE_SYSTEM_SCENARIO, "--out", out.string(), "--host-net", "none",
               "--camera-link", "shared"});
  ASSERT_TRUE(await_match([&] { return run.err_so_far(); }, "run-system: starting the rig"))
      << run.err_so_far();
  // While the nodes run: the script is in a network namespace of its own, and no veth pair of
  // its (tsysPID, alias tactile-run-system:PID:START) is on the host.
  const auto own_net = std::filesystem::read_symlink("/proc/self/ns/net");
  const auto run_net =
      std::filesystem::read_symlink("/proc/" + std::to_string(run.pid()) + "/ns/net");
  EXPECT_NE(run_net, own_net);
  const auto links = testing::run({"ip", "-o", "link", "show"});
  EXPECT_EQ(links.exit_code, 0);
  EXPECT_EQ(links.out.find("tsys" + std::to_string(run.pid())), std::string::npos) << links.out;
  EXPECT_EQ(links.out.find("tactile-run-system:" + std::to_string(run.pid()) + ":"),
            std::string::npos)
      << links.out;
  const auto r = run.wait(240s);
  ASSERT_FALSE(r.timed_out) << r.err;
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("run-system: --host-net none: the nodes' endpoints are not reachable from "
                       "the host\n"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("run-system: endpoints:"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out / "ipc"));
  EXPECT_NE(r.err.find("run-system: cameras 10.78.0.1,10.78.0.3 behind 1 link(s) shaped to 1gbit, "
                       "MTU 1500 (shared)"),
            std::string::npos)
      << r.err;
  // Every GVSP packet went through the link's queue, and none was dropped there.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.err, m, std::regex("camera link 0: Sent (\\d+) bytes (\\d+) pkt \\(dropped (\\d+)")))
      << r.err;
  EXPECT_GT(std::stoll(m[2].str()), 10000) << m[0];
  EXPECT_EQ(m[3].str(), "0") << m[0];
  // sensor_node opened the cameras at their link addresses with the region of interest and
  // packets that fit the MTU; the rig scored the frames, whole.
  const std::string sensor_log = util::read_file(out / "logs/sensor_node.log");
  for (const char* address : {"10.78.0.1", "10.78.0.3"})
    EXPECT_NE(sensor_log.find(address), std::string::npos) << address << "\n" << sensor_log;
  EXPECT_NE(sensor_log.find("region of interest at"), std::string::npos) << sensor_log;
  EXPECT_NE(sensor_log.find("packets 1500 B"), std::string::npos) << sensor_log;
  const std::string rig_log = util::read_file(out / "logs/rig.log");
  ASSERT_TRUE(std::regex_search(
      rig_log, m, std::regex("scored (\\d+) \\(unmatched \\d+, incomplete (\\d+)\\)")))
      << rig_log;
  EXPECT_GT(std::stoll(m[1].str()), 1000) << m[0];
  EXPECT_EQ(m[2].str(), "0") << m[0];
}

}  // namespace
}  // namespace tactile
