// tactile_web's update: the live model's state as JSON the page parses, whatever an event's text
// holds, and the --listen addresses it takes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "server.hpp"
#include "snapshot.hpp"

namespace tactile::web {
namespace {

TEST(WebSnapshot, IsJsonThePageReadsWithEveryValue) {
  live::LiveState s;
  s.now_ns = 1'763'700'000'123'000'000;
  s.phase = "TRANSPORT";
  s.cycle = 2;
  s.messages = 12345;
  live::FingertipView f;
  f.id = "left";
  f.sequence = 4242;
  f.status = "COMPLETE";
  f.touch = true;
  f.slip = true;
  f.max_fz_n = 1.25;
  for (std::uint32_t i = 0; i < 41; ++i)
    f.elements.push_back({i, i < 5, i == 4, 0.1 * i, -0.01 * i, 0.02 * i});
  f.elements[7].fz_n = std::numeric_limits<double>::quiet_NaN();  // never on the wire, still safe
  s.fingertips.push_back(f);
  s.events.push_back({1, "RECOMPRESS", "left e4 \"quoted\" back\\slash\nnew line \x01"});
  s.events_total = 9;

  control::Config c;
  c.f2_n = 3.0;
  SnapshotWriter w({}, c);
  std::string out;
  w.write(s, {17, 3, 1}, out);
  const auto j = nlohmann::json::parse(out);  // throws on anything a browser's JSON.parse refuses
  EXPECT_EQ(j["update"], 17);
  EXPECT_EQ(j["coalesced"], 3);
  EXPECT_EQ(j["streams"], 1);
  EXPECT_EQ(j["phase"], "TRANSPORT");
  EXPECT_EQ(j["cycle"], 2);
  EXPECT_EQ(j["f2_n"], 3.0);
  EXPECT_EQ(j["time_ns"], s.now_ns);
  const auto& l = j["fingertips"][0];
  EXPECT_EQ(l["id"], "left");
  EXPECT_EQ(l["sequence"], 4242);
  EXPECT_EQ(l["touch"], true);
  EXPECT_EQ(l["over"], false);
  ASSERT_EQ(l["elements"].size(), 41U);
  const auto& e4 = l["elements"][4];
  EXPECT_EQ(e4["id"], 4);
  EXPECT_EQ(e4["slip"], true);
  EXPECT_EQ(e4["fz"].get<double>(), 0.1 * 4);  // round trip, digit for digit
  EXPECT_EQ(e4["fx"].get<double>(), -0.01 * 4);
  EXPECT_EQ(e4["fy"].get<double>(), 0.02 * 4);
  EXPECT_EQ(l["elements"][7]["fz"], 0.0);
  // Without a calibration the elements sit on the rings: element 0 in the middle.
  EXPECT_EQ(l["elements"][0]["x"], 0.0);
  EXPECT_EQ(l["elements"][0]["y"], 0.0);
  EXPECT_EQ(j["events_total"], 9);
  EXPECT_EQ(j["events"][0]["detail"], s.events[0].detail);

  // The same buffer again: replaced, not appended to.
  w.write(s, {18, 3, 1}, out);
  EXPECT_EQ(nlohmann::json::parse(out)["update"], 18);
}

TEST(WebListen, TakesHostAndPortAndRefusesTheRest) {
  EXPECT_EQ(parse_listen("127.0.0.1:8080").host, "127.0.0.1");
  EXPECT_EQ(parse_listen("127.0.0.1:8080").port, 8080);
  EXPECT_EQ(parse_listen("0.0.0.0:0").port, 0);
  EXPECT_EQ(parse_listen("localhost:80").host, "localhost");
  for (const char* bad : {"8080", ":8080", "127.0.0.1:", "127.0.0.1:65536", "127.0.0.1:-1",
                          "127.0.0.1:80x", "example.org:80", "300.1.1.1:80"}) {
    EXPECT_THROW(parse_listen(bad), std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace tactile::web
