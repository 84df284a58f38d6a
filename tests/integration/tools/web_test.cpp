// tactile_web in a real browser: tactile_replay plays a known recording up to a frame into
// tactile_web, headless Chromium loads the page held at that frame (?freeze=SEQUENCE), and what
// the page wrote into the DOM is checked against the recording: the flags and phase at that
// frame, and a chosen element's force and shear.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <regex>

#include "tactile/control/config.hpp"
#include "tactile/wire/envelope.hpp"
#include "test_log.hpp"
#include "tools_support.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using testing::Process;
using testing::TempDir;
using tools_test::await_match;

constexpr std::uint64_t kFrame = 50;  // TOUCH, SLIP and OVER on the left fingertip
constexpr std::uint32_t kElement = 4;

struct Expected {
  bool touch = false, slip = false, over = false;
  v1::ElementReading element;
  bool element_slipping = false;
};

// An in-contact element slipping by the paper's rule: moved more than dr in this frame.
bool slipping(const v1::ElementReading& e, const control::Config& c) {
  return e.contact() && e.has_displacement() && std::hypot(e.dx_mm(), e.dy_mm()) > c.dr_mm;
}

// The fingertip's frame `kFrame` as the recording holds it, and its flags by the paper's rules
// as docs/control.md states them (TOUCH: some F_z > F1 or SLIP; SLIP: some element slipping;
// OVER: some F_z > F2), with the thresholds tactile_web runs with by default, outside Phase II.
Expected expected_from(const tools_test::LogContents& log, const std::string& sensor,
                       std::uint64_t frame = kFrame) {
  const control::Config c;
  Expected x;
  wire::EnvelopeDecoder decoder;
  for (const auto& rec : log.records) {
    if (rec.topic() != wire::frame_topic(sensor)) continue;
    EXPECT_EQ(decoder.decode(wire::bytes_of(rec.payload())), wire::DecodeStatus::kOk);
    const v1::TactileFrame& f = decoder.envelope().tactile_frame();
    if (f.sequence() != frame) continue;
    for (const auto& e : f.elements()) {
      if (e.id() == kElement) {
        x.element = e;
        x.element_slipping = slipping(e, c);
      }
      if (!e.contact()) continue;
      x.touch = x.touch || e.fz_n() > c.f1_n;
      x.over = x.over || e.fz_n() > c.f2_n;
      x.slip = x.slip || slipping(e, c);
    }
    x.touch = x.touch || x.slip;
    return x;
  }
  ADD_FAILURE() << "no frame " << frame << " of " << sensor << " in the recording";
  return x;
}

// The value of attribute `name` of the element whose id is `id`, in Chromium's dump of the DOM.
std::string attribute(const std::string& dom, const std::string& id, const std::string& name) {
  std::smatch m;
  const std::regex tag("<[^>]*\\sid=\"" + id + "\"[^>]*>");
  if (!std::regex_search(dom, m, tag)) return "(no element " + id + ")";
  const std::string t = m.str();
  const std::regex attr("\\s" + name + "=\"([^\"]*)\"");
  return std::regex_search(t, m, attr) ? m[1].str() : "(no " + name + " on " + id + ")";
}

// The text of the element whose id is `id` (no child elements).
std::string text(const std::string& dom, const std::string& id) {
  std::smatch m;
  const std::regex re("\\sid=\"" + id + "\"[^>]*>([^<]*)<");
  return std::regex_search(dom, m, re) ? m[1].str() : "(no element " + id + ")";
}

std::string fixed3(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}

// The page at `url` in Debian's headless Chromium, its DOM on standard output. Chromium as root
// needs --no-sandbox; a profile of its own leaves nothing behind. A page held by ?freeze= closes
// its stream, so the virtual time runs out and the DOM is dumped.
testing::ProcessResult page_dom(const std::string& url) {
  TempDir profile;
  Process chromium({"chromium", "--headless", "--no-sandbox", "--disable-gpu",
                    "--user-data-dir=" + profile.path().string(), "--no-first-run",
                    "--disable-extensions", "--disable-background-networking", "--disable-sync",
                    "--disable-component-update", "--no-default-browser-check",
                    "--virtual-time-budget=5000", "--dump-dom", url});
  return chromium.wait(60s);
}

TEST(Web, ChromiumShowsTheRecordingsFlagsPhaseAndForcesAtAFrame) {
  TempDir dir;
  const auto log_path = dir / "run.tlog";
  tools_test::write_test_log(log_path, false);
  const auto log = tools_test::read_log(log_path);

  // Frame k is recorded k * 10 ms after the first record: --to stops the replay after frame 50
  // of both fingertips, with the events of frames 3 and 28 before it.
  Process replay({TACTILE_REPLAY_PATH, log_path.string(), "--publish", "tcp://127.0.0.1:*",
                  "--as-fast-as-possible", "--wait-subscriptions", "3", "--to", "0.505",
                  "--wait-timeout", "20"});
  const auto endpoint =
      await_match([&] { return replay.err_so_far(); }, "publishing on (tcp://\\S+)");
  ASSERT_TRUE(endpoint) << replay.err_so_far();
  // The recording holds no hand_node Decisions: the page recomputes with the paper's rule, as
  // asked, and says so.
  Process web({TACTILE_WEB_PATH, *endpoint, "--listen", "127.0.0.1:0", "--recompute", "paper"});
  const auto url = await_match([&] { return web.out_so_far(); }, "serving (http://\\S+)");
  ASSERT_TRUE(url) << web.err_so_far();
  const auto played = replay.wait(20s);
  ASSERT_EQ(played.exit_code, 0) << played.err;

  const auto shown = page_dom(*url + "?freeze=" + std::to_string(kFrame));
  ASSERT_FALSE(shown.timed_out) << shown.err;
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  const std::string& dom = shown.out;

  // Held at the frame, for both fingertips.
  EXPECT_EQ(attribute(dom, "fingertip-left", "data-sequence"), "50") << dom;
  EXPECT_EQ(attribute(dom, "fingertip-right", "data-sequence"), "50");
  EXPECT_NE(dom.find("frozen at left 50, right 50"), std::string::npos);

  // Phase: the latest event before the frame (re-compress at frame 28, in TRANSPORT), a MOVE
  // step; both events listed.
  EXPECT_EQ(text(dom, "phase"), "TRANSPORT");
  EXPECT_EQ(attribute(dom, "flag-MOVE", "data-on"), "1");
  EXPECT_EQ(attribute(dom, "flag-SEARCH", "data-on"), "0");
  EXPECT_EQ(text(dom, "flags-by"), "flags: recomputed (paper)");
  EXPECT_EQ(attribute(dom, "flags-by", "data-from"), "recomputed");
  EXPECT_EQ(attribute(dom, "events", "data-total"), "2");
  EXPECT_TRUE(std::regex_search(dom, std::regex("<li>[0-9:.]+ RECOMPRESS left e4 re-compress</li>"
                                                "<li>[0-9:.]+ GRASPING_ENDED</li>")));

  for (const std::string sensor : {"left", "right"}) {
    SCOPED_TRACE(sensor);
    const Expected x = expected_from(log, sensor);
    for (const auto& [name, on] :
         {std::pair{"TOUCH", x.touch}, std::pair{"SLIP", x.slip}, std::pair{"OVER", x.over}}) {
      const std::string id = "flag-" + sensor + "-" + name;
      EXPECT_EQ(attribute(dom, id, "data-on"), on ? "1" : "0") << id;
      EXPECT_NE(attribute(dom, id, "class").find(on ? "flag on" : "flag off"), std::string::npos);
    }
    // The chosen element: the values the page holds, and the text it shows for them.
    const std::string el = "element-" + sensor + "-" + std::to_string(kElement);
    const v1::ElementReading& e = x.element;
    EXPECT_DOUBLE_EQ(std::stod(attribute(dom, el, "data-fz")), e.fz_n());
    EXPECT_DOUBLE_EQ(std::stod(attribute(dom, el, "data-fx")), e.fx_n());
    EXPECT_DOUBLE_EQ(std::stod(attribute(dom, el, "data-fy")), e.fy_n());
    EXPECT_TRUE(x.element_slipping);  // element 4 moves 0.008 mm in frame 50
    EXPECT_EQ(attribute(dom, el, "data-slip"), x.element_slipping ? "1" : "0");
    const std::string title = sensor + " e4: F_z " + fixed3(e.fz_n()) + " N, F_x " +
                              fixed3(e.fx_n()) + " N, F_y " + fixed3(e.fy_n()) + " N" +
                              (x.element_slipping ? ", slipping" : "");
    EXPECT_NE(dom.find("<title>" + title + "</title>"), std::string::npos) << title;
  }
  // The recording's frame 50: all three flags on, so a page stuck at another frame fails above.
  const Expected left = expected_from(log, "left");
  EXPECT_TRUE(left.touch && left.slip && left.over);

  web.signal(SIGINT);
  const auto stopped = web.wait(10s);
  EXPECT_EQ(stopped.exit_code, 0) << stopped.err;
}

// The start-up errors: a bad --listen is a usage error (2); Chart.js missing and a port in use
// (also by another tactile_web) are failures (1), each one line naming what to fix.
TEST(Web, RefusesABadListenAMissingChartJsAndAPortInUse) {
  auto r = testing::run({TACTILE_WEB_PATH, "tcp://127.0.0.1:9", "--listen", "8080"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--listen '8080': expected HOST:PORT"), std::string::npos) << r.err;
  r = testing::run({TACTILE_WEB_PATH, "tcp://127.0.0.1:9", "--listen", "127.0.0.1:0", "--chart-js",
                    "/nonexistent/chart.min.js"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err,
            "tactile_web: /nonexistent/chart.min.js: not found; the page's charts come from "
            "Debian's package libjs-chart.js (apt-get install libjs-chart.js)\n");
  r = testing::run({TACTILE_WEB_PATH});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tactile_web: give at least one endpoint"), std::string::npos) << r.err;

  Process first({TACTILE_WEB_PATH, "tcp://127.0.0.1:9", "--listen", "127.0.0.1:0"});
  const auto url =
      await_match([&] { return first.out_so_far(); }, "serving http://127.0.0.1:(\\d+)/");
  ASSERT_TRUE(url) << first.err_so_far();
  r = testing::run({TACTILE_WEB_PATH, "tcp://127.0.0.1:9", "--listen", "127.0.0.1:" + *url});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot listen on 127.0.0.1:" + *url), std::string::npos) << r.err;
  first.signal(SIGTERM);
  EXPECT_EQ(first.wait(10s).exit_code, 0);
}

// A connection to 127.0.0.1:port that sent `request` and reads only when asked: with a tiny
// receive buffer it stands for a browser that stopped reading.
class RawClient {
 public:
  RawClient(int port, const std::string& request) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    const int small = 1024;
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0 &&
                 ::send(fd_, request.data(), request.size(), MSG_NOSIGNAL) ==
                     static_cast<ssize_t>(request.size());
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  bool connected() const { return connected_; }
  // What arrives within `timeout` (bounded), up to `max` bytes.
  std::string read(std::chrono::milliseconds timeout, std::size_t max = 1 << 16) {
    std::string out;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    char buf[4096];
    while (out.size() < max && std::chrono::steady_clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      const auto n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) break;
      out.append(buf, static_cast<std::size_t>(n));
    }
    return out;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

// The tools' recording played as fast as possible into a tactile_web (on a free port, with
// `web_options`) that is its only subscriber besides the two the replay waits for.
class ReplayedIntoWeb {
 public:
  // `replay_options` added to tactile_replay's; `with_decisions`: hand_node's Decisions in the
  // recording (tools_test::write_test_log).
  explicit ReplayedIntoWeb(const std::vector<std::string>& web_options,
                           const std::vector<std::string>& replay_options = {},
                           bool with_decisions = false) {
    tools_test::write_test_log(log_path(), false, true, with_decisions);
    std::vector<std::string> replay{TACTILE_REPLAY_PATH,
                                    log_path().string(),
                                    "--publish",
                                    "tcp://127.0.0.1:*",
                                    "--as-fast-as-possible",
                                    "--wait-subscriptions",
                                    "3",
                                    "--wait-timeout",
                                    "20"};
    replay.insert(replay.end(), replay_options.begin(), replay_options.end());
    replay_.emplace(replay);
    const auto endpoint =
        await_match([&] { return replay_->err_so_far(); }, "publishing on (tcp://\\S+)");
    if (!endpoint) {
      error_ = replay_->err_so_far();
      return;
    }
    std::vector<std::string> argv{TACTILE_WEB_PATH, *endpoint, "--listen", "127.0.0.1:0"};
    argv.insert(argv.end(), web_options.begin(), web_options.end());
    web_.emplace(argv);
    const auto port =
        await_match([&] { return web_->out_so_far(); }, "serving http://127.0.0.1:(\\d+)/");
    if (!port) {
      error_ = web_->err_so_far();
      return;
    }
    port_ = std::stoi(*port);
  }
  bool started() const { return port_ > 0; }
  const std::string& error() const { return error_; }
  Process& replay() { return *replay_; }
  Process& web() { return *web_; }
  int port() const { return port_; }
  std::filesystem::path log_path() const { return dir_ / "run.tlog"; }

 private:
  TempDir dir_;
  std::optional<Process> replay_;
  std::optional<Process> web_;
  std::string error_;
  int port_ = 0;
};

// GET /state: the latest update, as tactile_web holds it.
std::string latest_update(int port) {
  RawClient c(port, "GET /state HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
  return c.read(2s);
}

// Two browsers that stopped reading hold the only two event streams: a third is refused (503),
// and every message still goes through the model (GET /state counts them) while they hang.
TEST(Web, StuckBrowsersNeverHoldUpTheSubscriberAndViewersAreBounded) {
  ReplayedIntoWeb run({"--max-viewers", "2", "--rate", "0"});
  ASSERT_TRUE(run.started()) << run.error();
  Process& replay = run.replay();
  Process& web = run.web();
  const int p = run.port();
  const std::string stream = "GET /stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  RawClient stuck1(p, stream);
  RawClient stuck2(p, stream);
  ASSERT_TRUE(stuck1.connected() && stuck2.connected());
  // Both streams are open once each has its first bytes (then they are never read again).
  EXPECT_NE(stuck1.read(5s, 100).find("200 OK"), std::string::npos);
  EXPECT_NE(stuck2.read(5s, 100).find("200 OK"), std::string::npos);
  RawClient third(p, stream);
  EXPECT_EQ(third.read(5s, 12).substr(0, 12), "HTTP/1.1 503");

  const auto played = replay.wait(20s);
  ASSERT_EQ(played.exit_code, 0) << played.err;
  // 100 frames of two fingertips and 4 events, about 2 MB of updates for each stream: all taken
  // in while both stuck streams are still open (a stuck stream is let go only after 2 s of not
  // taking its update).
  const auto taken = await_match([&] { return latest_update(p); },
                                 "\"streams\":(\\d+),\"time_ns\":\\d+,\"messages\":204,", 10s);
  ASSERT_TRUE(taken) << "tactile_web did not take in every message";
  EXPECT_EQ(*taken, "2");
  web.signal(SIGINT);
  const auto stopped = web.wait(10s);
  EXPECT_EQ(stopped.exit_code, 0) << stopped.err;
}

// A page that joins after the stream ended: it shows the final state at once and its charts hold
// the points of the updates before it joined (the 'history' event), not one point; without a
// --recompute and without hand_node's Decisions in the recording, it says that no one decided.
TEST(Web, APageThatJoinsLateFillsItsChartsAtOnce) {
  ReplayedIntoWeb run({"--rate", "0"});
  ASSERT_TRUE(run.started()) << run.error();
  const auto played = run.replay().wait(20s);
  ASSERT_EQ(played.exit_code, 0) << played.err;
  const int p = run.port();
  // Every message taken in before the page joins.
  ASSERT_TRUE(await_match([&] { return latest_update(p); }, "\"messages\":(204),", 10s));

  // The stream's first bytes: the charts' points before the latest update, then the update.
  RawClient late(p, "GET /stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  const std::string got = late.read(1s, 1 << 20);
  const std::string head = "event: history\ndata: [";
  const auto from = got.find(head);
  ASSERT_NE(from, std::string::npos) << got.substr(0, 400);
  const auto to = got.find("]\n\n", from);
  ASSERT_NE(to, std::string::npos);
  const std::string history = got.substr(from + head.size(), to - from - head.size());
  std::smatch m;
  std::ptrdiff_t points = 0;
  for (auto at = history.find("\"time_ns\":"); at != std::string::npos;
       at = history.find("\"time_ns\":", at + 1))
    ++points;
  // One point per update before the one sent with it (an update after every message here), at
  // most the 299 the page's charts keep besides it.
  ASSERT_TRUE(std::regex_search(got, m, std::regex("data: \\{\"update\":(\\d+),")));
  const long update = std::stol(m[1].str());
  EXPECT_GE(update, 204);
  EXPECT_EQ(points, std::min(update - 1, 299L)) << history.substr(0, 400);
  EXPECT_NE(got.find("data: {\"update\":"), std::string::npos);
  EXPECT_LT(got.find("event: history"), got.find("data: {\"update\":"));
  EXPECT_NE(got.find("\"flags_from\":\"none\""), std::string::npos);

  // The page in a browser: charts filled from the history, and no one's flags shown as decided.
  const auto shown = page_dom("http://127.0.0.1:" + std::to_string(p) + "/?freeze=99");
  ASSERT_FALSE(shown.timed_out) << shown.err;
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  EXPECT_EQ(attribute(shown.out, "fingertip-left", "data-sequence"), "99");
  const std::string chart_points = attribute(shown.out, "side", "data-chart-points");
  EXPECT_GE(std::atoi(chart_points.c_str()), 200) << chart_points;  // without history: 1
  EXPECT_EQ(attribute(shown.out, "fingertip-left", "data-decided"), "0");
  EXPECT_NE(text(shown.out, "flags-by").find("flags: no decisions from hand_node"),
            std::string::npos)
      << text(shown.out, "flags-by");

  run.web().signal(SIGINT);
  EXPECT_EQ(run.web().wait(10s).exit_code, 0);
}

// A recording with hand_node's Decisions that disagree with the paper's rule, played up to frame
// 55 (and its Decision): the page shows hand_node's flags and slipping element, named by its
// detector, where the paper's rule would show no slip at all (nothing moves in frame 55).
TEST(Web, ChromiumShowsHandNodesDecisionsNotThePapersRule) {
  ReplayedIntoWeb run({"--rate", "0"}, {"--to", "0.5505"}, true);
  ASSERT_TRUE(run.started()) << run.error();
  const auto played = run.replay().wait(20s);
  ASSERT_EQ(played.exit_code, 0) << played.err;
  // Frames 0-55 of both fingertips, their 56 Decisions and 3 events taken in.
  ASSERT_TRUE(await_match([&] { return latest_update(run.port()); }, "\"messages\":(171),", 10s));
  const auto shown = page_dom("http://127.0.0.1:" + std::to_string(run.port()) + "/?freeze=55");
  ASSERT_FALSE(shown.timed_out) << shown.err;
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  const std::string& dom = shown.out;
  EXPECT_EQ(attribute(dom, "fingertip-left", "data-sequence"), "55") << dom;
  EXPECT_EQ(text(dom, "flags-by"), "flags: hand_node (learned)");
  EXPECT_EQ(attribute(dom, "fingertip-left", "data-decided"), "1");
  EXPECT_EQ(attribute(dom, "flag-left-SLIP", "data-on"), "1");
  EXPECT_EQ(attribute(dom, "flag-right-SLIP", "data-on"), "0");
  EXPECT_EQ(attribute(dom, "element-left-7", "data-slip"), "1");
  EXPECT_EQ(attribute(dom, "element-left-4", "data-slip"), "0");
  // The paper's rule on frame 55 of the recording: no element moves beyond dr.
  const auto log = tools_test::read_log(run.log_path());
  EXPECT_FALSE(expected_from(log, "left", 55).slip);
  run.web().signal(SIGINT);
  EXPECT_EQ(run.web().wait(10s).exit_code, 0);
}

}  // namespace
}  // namespace tactile
