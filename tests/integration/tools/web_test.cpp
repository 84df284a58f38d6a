// tactile_web in a real browser: tactile_replay plays a known recording up to a frame into
// tactile_web, headless Chromium loads the page held at that frame (?freeze=SEQUENCE), and what
// the page wrote into the DOM is checked against the recording: the flags and phase at that
// frame, and a chosen element's force and shear.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <cstdio>
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
Expected expected_from(const tools_test::LogContents& log, const std::string& sensor) {
  const control::Config c;
  Expected x;
  wire::EnvelopeDecoder decoder;
  for (const auto& rec : log.records) {
    if (rec.topic() != wire::frame_topic(sensor)) continue;
    EXPECT_EQ(decoder.decode(wire::bytes_of(rec.payload())), wire::DecodeStatus::kOk);
    const v1::TactileFrame& f = decoder.envelope().tactile_frame();
    if (f.sequence() != kFrame) continue;
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
  ADD_FAILURE() << "no frame " << kFrame << " of " << sensor << " in the recording";
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
  Process web({TACTILE_WEB_PATH, *endpoint, "--listen", "127.0.0.1:0"});
  const auto url = await_match([&] { return web.out_so_far(); }, "serving (http://\\S+)");
  ASSERT_TRUE(url) << web.err_so_far();
  const auto played = replay.wait(20s);
  ASSERT_EQ(played.exit_code, 0) << played.err;

  // Chromium as root needs --no-sandbox; a profile of its own leaves nothing behind. The page
  // closes its stream once held, so the virtual time runs out and the DOM is dumped.
  TempDir profile;
  Process chromium({"chromium", "--headless", "--no-sandbox", "--disable-gpu",
                    "--user-data-dir=" + profile.path().string(), "--no-first-run",
                    "--disable-extensions", "--disable-background-networking", "--disable-sync",
                    "--disable-component-update", "--no-default-browser-check",
                    "--virtual-time-budget=5000", "--dump-dom",
                    *url + "?freeze=" + std::to_string(kFrame)});
  const auto shown = chromium.wait(60s);
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

}  // namespace
}  // namespace tactile
