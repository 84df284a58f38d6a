#pragma once

// The cameras' link for a run of the latency benchmark: behind shaped veth pairs
// (scripts/camera-link, in a network namespace of their own) or on loopback beside the nodes, and
// the link alone measured with bursts of datagrams the size of a frame's packets.
#include <array>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "latency_report.hpp"
#include "supervision.hpp"
#include "tactile/util/clock.hpp"

namespace tactile::bench {

constexpr const char* kCameraAddresses[2] = {"127.0.0.2", "127.0.0.3"};

// The cameras behind a shaped link for one run (scripts/camera-link, started from this network
// namespace and stopped at the end, with its queue counters), or on loopback beside the nodes.
class CameraLink {
 public:
  CameraLink(const Settings& s, const fs::path& log) : log_(log) {
    if (s.camera_link == "loopback") return;
    // The logs are appended to (every run of --runs, and an --out directory used again): only
    // what this camera-link writes names this link's namespace.
    std::error_code size_error;
    const auto start = fs::file_size(log, size_error);
    const std::streamoff from = size_error ? 0 : static_cast<std::streamoff>(start);
    child_.emplace("camera-link",
                   std::vector<std::string>{
                       "/bin/bash", (fs::path(TACTILE_SOURCE_DIR) / "scripts/camera-link").string(),
                       s.camera_link, "--rate", s.link_rate, "--mtu", std::to_string(s.link_mtu)},
                   log);
    // Its first line: "cameras A,B netns NS links N".
    const std::int64_t deadline = util::monotonic_ns() + 20'000'000'000;
    while (util::monotonic_ns() < deadline) {
      std::ifstream in(log);
      in.seekg(from);
      for (std::string line; std::getline(in, line);) {
        std::istringstream words(line);
        std::string c, cameras, n, netns, l, links, o, nodes, b;
        if (words >> c >> cameras >> n >> netns >> l >> links >> o >> nodes >> b >> burst_ &&
            c == "cameras" && n == "netns" && o == "nodes" && b == "burst") {
          const auto comma = cameras.find(',');
          cameras_ = {cameras.substr(0, comma), cameras.substr(comma + 1)};
          netns_ = netns;
          node_ = nodes.substr(0, nodes.find(','));
          return;
        }
      }
      if (!child_->running()) break;
      std::this_thread::sleep_for(milliseconds(20));
    }
    child_->stop(milliseconds(3000));
    throw std::runtime_error(
        fmt::format("the {} camera link did not come up:{}", s.camera_link, tail_of(log)));
  }
  CameraLink(const CameraLink&) = delete;
  CameraLink& operator=(const CameraLink&) = delete;

  const std::array<std::string, 2>& cameras() const { return cameras_; }
  bool shaped() const { return child_.has_value(); }
  const std::string& netns() const { return netns_; }
  // The nodes' end of the (first) link.
  const std::string& node_address() const { return node_; }
  // The token bucket's burst, bytes.
  int burst() const { return burst_; }
  // rig's options for it (none on loopback, where its cameras are where they always are).
  std::vector<std::string> rig_options() const {
    if (!child_) return {};
    return {"--cameras", cameras_[0] + "," + cameras_[1], "--camera-netns", netns_};
  }
  // Stops it; the link(s)' counters, summed ("camera-link: camera link I: Sent B bytes P pkt
  // (dropped D, overlimits O ...").
  LinkCounters stop() {
    LinkCounters c;
    if (!child_) return c;
    c.burst = burst_;
    child_->stop(milliseconds(5000));
    std::ifstream in(log_);
    const std::regex re(
        "camera link \\d+: Sent (\\d+) bytes (\\d+) pkt \\(dropped (\\d+), overlimits (\\d+)");
    for (std::string line; std::getline(in, line);) {
      std::smatch m;
      if (!std::regex_search(line, m, re)) continue;
      c.bytes += std::stoull(m[1]);
      c.packets += std::stoull(m[2]);
      c.dropped += std::stoull(m[3]);
      c.overlimits += std::stoull(m[4]);
      c.known = true;
    }
    return c;
  }

 private:
  fs::path log_;
  std::optional<Child> child_;
  std::array<std::string, 2> cameras_{kCameraAddresses[0], kCameraAddresses[1]};
  std::string netns_;
  std::string node_;
  int burst_ = 0;
};

// The link alone: `bursts` times, UDP datagrams of the sizes given (one exposure's GVSP packets:
// both frames on a shared link, one on a link of its own) sent at once with sendmmsg from the
// cameras' namespace to the nodes' end of the (first) link, 20 ms apart; the time from each
// burst's send to its last datagram received, over the bursts that arrived whole. What the
// emulated wire itself takes, to set beside the frame's computed wire time.
Dist probe_link(const CameraLink& link, const std::vector<std::size_t>& sizes, int bursts);

}  // namespace tactile::bench
