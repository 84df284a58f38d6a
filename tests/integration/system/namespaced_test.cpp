// The compose topology without Docker: rig, sensor_node and hand_node each in a network
// namespace of its own, joined by veth pairs to three bridges (control, camera_left,
// camera_right) with the addresses of docker/compose.yaml, running docker/config's files. This is
// the two-machine lab in miniature: nothing talks over loopback.
#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "process.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using testing::Process;
using testing::TempDir;

const std::filesystem::path kSource = TACTILE_SOURCE_DIR;

void ip(const std::vector<std::string>& args) {
  std::vector<std::string> argv{"ip"};
  argv.insert(argv.end(), args.begin(), args.end());
  const auto r = testing::run(argv, 10s);
  if (r.exit_code != 0) {
    std::string cmd;
    for (const auto& a : argv)
      cmd += a + " ";
    throw std::runtime_error("'" + cmd + "' failed: " + r.err);
  }
}

// The owner of the namespaces a Network makes, "PID-START" (START the process's start time,
// /proc/PID/stat field 22, so a reused PID is not taken for it; scripts/lib/leftovers.sh); empty
// when PID does not run.
std::string owner_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  if (!std::getline(in, stat) || stat.rfind(')') == std::string::npos) return "";
  // After the command name (which may hold spaces): field 3 onwards.
  std::istringstream fields(stat.substr(stat.rfind(')') + 2));
  std::string field;
  for (int i = 3; i <= 22 && fields >> field; ++i) {
  }
  return std::to_string(pid) + "-" + field;
}

// The namespaces of a test that was killed before its Network went (tsc-HOST-PID-START whose
// owner no longer runs): what still runs in them is killed and they are deleted, with a line
// each (docs/reliability.md, "What a killed run leaves").
void remove_leftovers() {
  const auto list = testing::run({"ip", "netns", "list"}, 10s);
  std::istringstream lines(list.out);
  std::string line;
  const std::regex ours("^(tsc-(br|rig|sen|hand)-(([0-9]+)-[0-9]+))( .*)?$");
  std::smatch m;
  while (std::getline(lines, line)) {
    if (!std::regex_match(line, m, ours) || owner_of(std::stoi(m[4].str())) == m[3].str()) continue;
    const std::string ns = m[1].str();
    std::istringstream pids(testing::run({"ip", "netns", "pids", ns}, 10s).out);
    for (std::string pid; pids >> pid;)
      ::kill(std::stoi(pid), SIGKILL);
    if (testing::run({"ip", "netns", "del", ns}, 10s).exit_code == 0)
      std::fprintf(stderr,
                   "namespaced_system_test: removed namespace %s left by an earlier run (pid %s, "
                   "no longer running)\n",
                   ns.c_str(), m[4].str().c_str());
  }
}

// Three hosts and a switch; everything is deleted when the object goes.
class Network {
 public:
  Network() : tag_(owner_of(::getpid())) {
    remove_leftovers();
    for (const char* h : {"br", "rig", "sen", "hand"}) {
      const std::string ns = name(h);
      ip({"netns", "add", ns});
      made_.push_back(ns);
      ip({"-n", ns, "link", "set", "lo", "up"});
    }
    const std::string br = name("br");
    struct Net {
      const char* bridge;
      int mtu;
    };
    const Net nets[] = {{"control", 1500}, {"camleft", 9000}, {"camright", 9000}};
    for (const Net& n : nets) {
      ip({"-n", br, "link", "add", n.bridge, "type", "bridge"});
      ip({"-n", br, "link", "set", n.bridge, "mtu", std::to_string(n.mtu), "up"});
    }
    // host, network index, address
    struct Port {
      const char* host;
      int net;
      const char* address;
    };
    const Port ports[] = {{"rig", 0, "172.28.0.10"}, {"rig", 1, "172.28.1.10"},
                          {"rig", 2, "172.28.2.10"}, {"sen", 0, "172.28.0.20"},
                          {"sen", 1, "172.28.1.20"}, {"sen", 2, "172.28.2.20"},
                          {"hand", 0, "172.28.0.30"}};
    for (const Port& p : ports) {
      const std::string dev = std::string(p.host) + std::to_string(p.net);
      const std::string peer = "p-" + dev;
      const std::string mtu = std::to_string(nets[p.net].mtu);
      ip({"-n", br, "link", "add", dev, "mtu", mtu, "type", "veth", "peer", "name", peer, "mtu",
          mtu});
      ip({"-n", br, "link", "set", peer, "master", nets[p.net].bridge, "up"});
      ip({"-n", br, "link", "set", dev, "netns", name(p.host)});
      ip({"-n", name(p.host), "addr", "add", std::string(p.address) + "/24", "dev", dev});
      ip({"-n", name(p.host), "link", "set", dev, "up"});
    }
  }
  ~Network() {
    for (const auto& ns : made_)
      testing::run({"ip", "netns", "del", ns}, 10s);
  }
  std::string name(const std::string& host) const { return "tsc-" + host + "-" + tag_; }
  std::vector<std::string> in(const std::string& host, std::vector<std::string> argv) const {
    std::vector<std::string> all{"ip", "netns", "exec", name(host)};
    all.insert(all.end(), argv.begin(), argv.end());
    return all;
  }

 private:
  std::string tag_;
  std::vector<std::string> made_;
};

// A killed test's namespaces (a stand-in: its owner's PID with a start time it never had) go;
// another's that runs (this process) stay. tests/integration/system/killed_run_test.sh kills a
// real run and has this test remove what it left.
TEST(NamespacedSystem, RemovesTheNamespacesOfAKilledRunAndNoOthers) {
  ASSERT_EQ(::geteuid(), 0U) << "network namespaces need root (CI runs as root)";
  const std::string dead = "tsc-br-" + std::to_string(::getpid()) + "-1";
  const std::string live = "tsc-hand-" + owner_of(::getpid());
  ip({"netns", "add", dead});
  ip({"netns", "add", live});
  ::testing::internal::CaptureStderr();
  remove_leftovers();
  const std::string said = ::testing::internal::GetCapturedStderr();
  std::fputs(said.c_str(), stderr);
  const std::string names = testing::run({"ip", "netns", "list"}, 10s).out;
  testing::run({"ip", "netns", "del", live}, 10s);
  testing::run({"ip", "netns", "del", dead}, 10s);
  EXPECT_EQ(names.find(dead), std::string::npos) << names;
  EXPECT_NE(names.find(live), std::string::npos) << names;
  EXPECT_NE(said.find("removed namespace " + dead + " left by an earlier run (pid " +
                      std::to_string(::getpid()) + ", no longer running)"),
            std::string::npos)
      << said;
}

TEST(NamespacedSystem, RunsTheComposeTopologyWithDockersConfiguration) {
  ASSERT_EQ(::geteuid(), 0U)
      << "network namespaces joined by veth pairs need root (CI runs as root)";
  Network net;
  TempDir out;
  const std::string config = (kSource / "docker/config").string();
  Process rig(net.in(
      "rig",
      {TACTILE_RIG_PATH, "--scenario", (kSource / "rig/scenarios/default.yaml").string(),
       "--cameras", "172.28.1.10,172.28.2.10", "--observe-frames", "tcp://172.28.0.20:5555",
       "--observe-events", "tcp://172.28.0.30:5558", "--report", (out / "report.json").string()}));
  Process sensor(net.in("sen", {TACTILE_SENSOR_NODE_PATH, "--config", config + "/sensor_node.yaml",
                                "--state-dir", out.path().string()}));
  Process hand(net.in("hand", {TACTILE_HAND_NODE_PATH, "--config", config + "/hand_node.yaml"}));
  // The rig ends the scenario; hand_node ends its task just before (after a drop it would hold
  // for ever on stale data, and is given 20 s).
  const auto r = rig.wait(180s);
  const auto h = hand.wait(20s);
  sensor.signal(SIGINT);
  const auto s = sensor.wait(20s);
  const std::string logs =
      "\n--- hand\n" + h.err + "\n--- sensor\n" + s.err + "\n--- rig\n" + r.err;
  EXPECT_FALSE(h.timed_out) << logs;
  EXPECT_EQ(h.exit_code, 0) << logs;
  EXPECT_EQ(r.exit_code, 0) << logs;
  EXPECT_EQ(s.exit_code, 0) << logs;
  std::ifstream in(out / "report.json");
  ASSERT_TRUE(in) << logs;
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["completed"], true) << report.dump();
  EXPECT_EQ(report["dropped"], false) << report.dump();
  EXPECT_EQ(report["tightened_cycle"], report["true_tight_cycle"]) << report.dump();
  // The cap's weight slips on lift in only a few frames; a real-time run may miss them (a missed
  // classification only means the lift goes on), but it must never call the lift a release.
  EXPECT_NE(report["grasp_classified"], "release") << report.dump();
  EXPECT_EQ(report["release_classified"], "release") << report.dump();
  ASSERT_TRUE(report["latency_ms"].is_object()) << report.dump();
  // For docs/docker.md's comparison of loopback, namespaces and Docker's bridges.
  std::printf("NamespacedSystem: latency_ms %s\n", report["latency_ms"].dump().c_str());
  // The GigE Vision packets crossed veth links with a 9000-byte MTU in 8192-byte packets: the
  // frames arrived whole (the rig counts the incomplete frames sensor_node published).
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.err, m, std::regex("incomplete ([0-9]+)\\)"))) << r.err;
  EXPECT_LE(std::stoi(m[1].str()), 5) << m[0];
}

}  // namespace
}  // namespace tactile
