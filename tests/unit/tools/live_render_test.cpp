// tactile_live's screen as a pure function of its state: golden texts of a fixed state in a
// large, a narrow and a tiny window, with and without colour; and the model fed real messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <sstream>
#include <utility>
#include <vector>

#include "dashboard.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/util/files.hpp"
#include "tactile/wire/envelope.hpp"
#include "viewer.hpp"

namespace tactile::live {
namespace {

LiveState fixed_state() {
  LiveState s;
  s.now_ns = 1'763'700'000'123'000'000;  // a fixed instant
  s.messages = 12345;
  s.phase = "TWIST_TURN";
  s.cycle = 2;
  s.flags_from = FlagSource::kHandNode;
  s.detector = "learned";
  s.rates = {{wire::frame_topic("left"), 100.0},
             {wire::frame_topic("right"), 99.5},
             {wire::kEventTopic, 0.5},
             {wire::stats_topic("left"), 1.0}};
  for (const char* id : {"left", "right"}) {
    FingertipView f;
    f.id = id;
    f.sequence = std::string(id) == "left" ? 4242 : 4240;
    f.status = "COMPLETE";
    f.fps = std::string(id) == "left" ? 100.0 : 99.5;
    f.lost = std::string(id) == "left" ? 0 : 2;
    f.decided = true;
    for (std::uint32_t e = 0; e < 41; ++e) {
      ElementCell c;
      c.id = e;
      if (std::string(id) == "left" && (e < 9 || e == 20 || e == 33)) {
        c.contact = true;
        c.fz_n = 0.3 * e;
        c.slip = e == 3 || e == 20;
      }
      f.elements.push_back(c);
    }
    if (std::string(id) == "left") {
      f.touch = true;
      f.slip = true;
      f.max_fz_n = 9.9;
      f.over = true;
      f.max_slip_mm = 0.0061;
      f.has_stats = true;
      f.camera_frames = 4300;
      f.incomplete = 3;
      f.measure_us_p50 = 41.0;
    }
    s.fingertips.push_back(f);
  }
  s.events = {{1'763'700'000'000'000'000, "PHASE", "TWIST_TURN"},
              {1'763'700'000'050'000'000, "RECOMPRESS", "left e3 1.2"},
              {1'763'700'000'100'000'000, "TWIST_CYCLE", "cycle 2"}};
  return s;
}

void check_golden(const std::string& name, const std::string& text) {
  const std::filesystem::path file = std::filesystem::path(TACTILE_GOLDEN_DIR) / (name + ".txt");
  if (std::getenv("TACTILE_UPDATE_GOLDEN") != nullptr) util::write_file_atomic(file, text);
  ASSERT_TRUE(std::filesystem::exists(file)) << file;
  EXPECT_EQ(text, util::read_file(file)) << "golden " << file << "; the new text:\n" << text;
}

void check_fits(const std::string& text, int width, int height) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    EXPECT_LE(static_cast<int>(line.size()), width) << line;
  }
  EXPECT_LE(n, height);
}

TEST(LiveRender, LargeWindowShowsBothDomesSideBySide) {
  RenderOptions o;
  o.width = 100;
  o.height = 40;
  const std::string text = render(fixed_state(), {}, o);
  check_fits(text, o.width, o.height);
  check_golden("live_100x40", text);
}

TEST(LiveRender, NarrowWindowStacksTheDomes) {
  RenderOptions o;
  o.width = 50;
  o.height = 40;
  const std::string text = render(fixed_state(), {}, o);
  check_fits(text, o.width, o.height);
  check_golden("live_50x40", text);
}

TEST(LiveRender, TinyWindowKeepsTheSummaries) {
  RenderOptions o;
  o.width = 40;
  o.height = 12;
  const std::string text = render(fixed_state(), {}, o);
  check_fits(text, o.width, o.height);
  check_golden("live_40x12", text);
}

std::vector<FingertipView> tips(std::initializer_list<const char*> ids) {
  std::vector<FingertipView> out;
  for (const char* id : ids) {
    FingertipView f;
    f.id = id;
    out.push_back(f);
  }
  return out;
}

TEST(ScreenLayout, DrawsLeftOnTheLeftWhateverOrderTheFramesArrivedIn) {
  EXPECT_EQ(screen_layout(tips({"right", "left"}), 100, 40, 3).order,
            (std::vector<std::size_t>{1, 0}));
  EXPECT_EQ(screen_layout(tips({"left", "right"}), 100, 40, 3).order,
            (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(screen_layout(tips({"right", "thumb", "left", "index"}), 200, 40, 3).order,
            (std::vector<std::size_t>{2, 3, 1, 0}));
}

TEST(ScreenLayout, UsesTheWholeWindow) {
  const auto both = tips({"left", "right"});
  // Side by side, each block takes its half of any width, and the domes grow with the window.
  const ScreenLayout small = screen_layout(both, 80, 24, 3);
  EXPECT_TRUE(small.side_by_side);
  EXPECT_EQ(small.block_width, 40);
  const ScreenLayout large = screen_layout(both, 240, 50, 3);
  EXPECT_TRUE(large.side_by_side);
  EXPECT_EQ(large.block_width, 120);
  EXPECT_EQ(large.grid_rows, 50 - 3 - 3 - 3 - 1);
  EXPECT_GT(large.grid_rows, small.grid_rows);
  // A dome is as tall as its block's width allows: a taller window gives the events the rest.
  EXPECT_EQ(screen_layout(both, 80, 200, 3).grid_rows, (40 - 4) / 2 + 1);
  // Too narrow for two blocks: stacked, each the whole width.
  const ScreenLayout narrow = screen_layout(both, 50, 40, 3);
  EXPECT_FALSE(narrow.side_by_side);
  EXPECT_EQ(narrow.block_width, 50);
  EXPECT_EQ(narrow.grid_rows, (40 - 6) / 2 - 3);
  // Too small for a dome: summaries only.
  EXPECT_EQ(screen_layout(both, 40, 12, 3).grid_rows, 0);
}

TEST(LiveRender, TheLeftFingertipIsDrawnOnTheLeftWhenTheRightArrivedFirst) {
  LiveState s = fixed_state();
  std::swap(s.fingertips[0], s.fingertips[1]);
  RenderOptions o;
  o.width = 100;
  o.height = 40;
  EXPECT_EQ(render(s, {}, o), render(fixed_state(), {}, o));
}

TEST(LiveRender, ColourMarksSlipAndOverWithEscapeCodesOnly) {
  RenderOptions o;
  o.width = 100;
  o.height = 40;
  o.color = true;
  const std::string colored = render(fixed_state(), {}, o);
  EXPECT_NE(colored.find("\x1b[41;97m"), std::string::npos);  // slip: white on red
  EXPECT_NE(colored.find("\x1b[1;31m#"), std::string::npos);  // over F2
  // Without its escape codes it is the plain picture but for the legend and the slip glyphs.
  std::string stripped;
  for (std::size_t i = 0; i < colored.size(); ++i) {
    if (colored[i] == '\x1b') {
      while (colored[i] != 'm')
        ++i;
      continue;
    }
    stripped += colored[i];
  }
  check_fits(stripped, o.width + 1, o.height);  // padded blocks keep their trailing blanks
}

TEST(LiveRender, DomeLayoutIsTheRingsOrTheCalibration) {
  const auto rings = dome_layout(41, nullptr);
  ASSERT_EQ(rings.size(), 41U);
  EXPECT_DOUBLE_EQ(rings[0][0], 0.0);
  EXPECT_DOUBLE_EQ(rings[1][0], 1.0);   // ring 1: 8 elements at radius 1
  EXPECT_DOUBLE_EQ(rings[9][0], 2.0);   // ring 2: 16 at radius 2
  EXPECT_DOUBLE_EQ(rings[25][0], 3.0);  // ring 3: 16 at radius 3
  Calibration cal;
  cal.elements.resize(2);
  cal.elements[1].center_px = {10, 20};
  const auto c = dome_layout(2, &cal);
  EXPECT_DOUBLE_EQ(c[1][0], 10.0);
  EXPECT_DOUBLE_EQ(c[1][1], 20.0);
}

// Recomputed with the paper's rule (hand_node's decisions are shown by default: see
// viewers_decision_test.cpp).
TEST(LiveModel, FramesEventsAndStatsBecomeTheState) {
  LiveModel m({control::Config{}, 8, control::SlipDetectorKind::kPaper});
  v1::Envelope env;
  std::string buf;
  std::int64_t now = 1'000'000'000;
  for (const std::uint64_t seq : {0, 1, 2, 5}) {  // 3 and 4 are lost
    auto* f = env.mutable_tactile_frame();
    f->Clear();
    f->set_sensor_id("left");
    f->set_sequence(seq);
    f->set_status(v1::FRAME_STATUS_COMPLETE);
    for (std::uint32_t e = 0; e < 41; ++e) {
      auto* r = f->add_elements();
      r->set_id(e);
      if (e == 7) {
        r->set_contact(true);
        r->set_fz_n(3.0);  // over F2
        r->set_has_displacement(seq > 0);
        r->set_dy_mm(0.01);  // slip
      }
    }
    wire::encode(env, buf);
    EXPECT_EQ(m.add(wire::frame_topic("left"), wire::bytes_of(buf), now), -1);
    now += 10'000'000;
  }
  auto* ev = env.mutable_event();
  ev->set_time_ns(5);
  ev->set_kind(v1::EVENT_KIND_TWIST_CYCLE);
  ev->set_phase("TWIST_TURN");
  ev->set_cycle(3);
  wire::encode(env, buf);
  EXPECT_EQ(m.add(wire::kEventTopic, wire::bytes_of(buf), now), 0);
  auto* st = env.mutable_sensor_stats();
  st->set_sensor_id("left");
  st->set_frames(77);
  wire::encode(env, buf);
  m.add(wire::stats_topic("left"), wire::bytes_of(buf), now);
  EXPECT_EQ(m.add(wire::frame_topic("left"), wire::bytes_of("garbage"), now), -1);
  m.tick(now + 2'000'000'000, 42);
  const LiveState& s = m.state();
  ASSERT_EQ(s.fingertips.size(), 1U);
  const FingertipView& f = s.fingertips[0];
  EXPECT_EQ(f.sequence, 5U);
  EXPECT_EQ(f.lost, 2U);
  EXPECT_TRUE(f.over);
  EXPECT_TRUE(f.slip);
  EXPECT_TRUE(f.elements[7].slip);
  EXPECT_FALSE(f.elements[6].contact);
  EXPECT_TRUE(f.has_stats);
  EXPECT_EQ(f.camera_frames, 77U);
  EXPECT_EQ(s.phase, "TWIST_TURN");
  EXPECT_EQ(s.cycle, 3U);
  ASSERT_EQ(s.events.size(), 1U);
  EXPECT_EQ(s.events[0].kind, "TWIST_CYCLE");
  EXPECT_EQ(s.messages, 7U);
  EXPECT_EQ(s.undecodable, 1U);
  EXPECT_NE(summary_lines(s).find("left seq=5 "), std::string::npos) << summary_lines(s);
  EXPECT_NE(summary_lines(s).find("flags=TOUCH,SLIP,OVER slipping=7 by=recomputed "
                                  "detector=paper phase=TWIST_TURN"),
            std::string::npos)
      << summary_lines(s);
}

// --calibration as --help shows it, FILE ...: the list ends at the first endpoint, which with
// the rest joins the endpoints, wherever the endpoints stand.
TEST(ViewerOptions, CalibrationListEndsAtTheFirstEndpoint) {
  const auto parse = [](std::vector<std::string> args) {
    ViewerOptions o;
    CLI::App app;
    add_viewer_options(app, o, "F2");
    std::reverse(args.begin(), args.end());  // CLI11 takes a vector of arguments last first
    app.parse(args);
    settle_endpoints(o);
    return o;
  };
  ViewerOptions o =
      parse({"--calibration", "a.yaml", "b.yaml", "tcp://127.0.0.1:5555", "ipc:///tmp/events"});
  EXPECT_EQ(o.calibrations, (std::vector<std::string>{"a.yaml", "b.yaml"}));
  EXPECT_EQ(o.endpoints, (std::vector<std::string>{"tcp://127.0.0.1:5555", "ipc:///tmp/events"}));
  o = parse({"tcp://127.0.0.1:5555", "--calibration", "a.yaml", "b.yaml", "--f2", "3"});
  EXPECT_EQ(o.calibrations, (std::vector<std::string>{"a.yaml", "b.yaml"}));
  EXPECT_EQ(o.endpoints, (std::vector<std::string>{"tcp://127.0.0.1:5555"}));
  o = parse({"--calibration", "a.yaml", "--calibration", "b.yaml", "tcp://127.0.0.1:5555"});
  EXPECT_EQ(o.calibrations, (std::vector<std::string>{"a.yaml", "b.yaml"}));
  EXPECT_EQ(o.endpoints, (std::vector<std::string>{"tcp://127.0.0.1:5555"}));
  EXPECT_THROW(parse({"--calibration", "a.yaml", "b.yaml"}), cli::UsageError);
  ViewerOptions shown;
  CLI::App app;
  add_viewer_options(app, shown, "F2");
  EXPECT_NE(app.help().find("--calibration FILE ..."), std::string::npos) << app.help();
}

}  // namespace
}  // namespace tactile::live
