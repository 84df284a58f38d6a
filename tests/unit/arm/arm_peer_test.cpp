// Who the arm answers and its deadman (docs/arm.md, "Timing"), with time as an argument: no
// clock, no socket. The cases are a table shared with the Python arm side's ArmPeer
// (tests/data/arm_link/arm_peer_cases.json, its format in its "about"): both implementations
// are held to the same rows.
#include "tactile/arm/arm_peer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

namespace tactile::arm {
namespace {

using nlohmann::json;

const std::filesystem::path kCases = std::filesystem::path(TACTILE_SOURCE_DIR) / "tests" / "data" /
                                     "arm_link" / "arm_peer_cases.json";

std::int64_t ns_of_ms(const json& ms) {
  return std::llround(ms.get<double>() * 1e6);
}

void expect_heard(const ArmPeer::Heard& h, const json& want) {
  for (const auto& [key, value] : want.items()) {
    EXPECT_TRUE(key == "accepted" || key == "connected" || key == "new_client" || key == "resumed")
        << "unknown field " << key;
  }
  EXPECT_EQ(h.accepted, want.value("accepted", false));
  EXPECT_EQ(h.connected, want.value("connected", false));
  EXPECT_EQ(h.new_client, want.value("new_client", false));
  EXPECT_EQ(h.resumed, want.value("resumed", false));
}

void expect_state(const ArmPeer& p, const json& then) {
  for (const auto& [key, value] : then.items()) {
    if (key == "has_peer") {
      EXPECT_EQ(p.has_peer(), value.get<bool>());
    } else if (key == "peer") {
      EXPECT_EQ(p.peer(), value.get<std::string>());
    } else if (key == "held") {
      EXPECT_EQ(p.held(), value.get<bool>());
    } else if (key == "last_heard_ms") {
      EXPECT_EQ(p.last_heard_ns(), ns_of_ms(value));
    } else {
      ADD_FAILURE() << "unknown state " << key;
    }
  }
}

// One step of a case; returns what it did.
std::string run_step(ArmPeer& p, const json& step) {
  const auto what = step.at("do").get<std::string>();
  if (what == "heartbeat") {
    expect_heard(p.heartbeat(step.at("from").get<std::string>(), ns_of_ms(step.at("t_ms"))),
                 step.at("heard"));
  } else if (what == "command") {
    expect_heard(p.command(step.at("from").get<std::string>(), ns_of_ms(step.at("t_ms"))),
                 step.at("heard"));
  } else if (what == "deadman_trips") {
    EXPECT_EQ(p.deadman_trips(ns_of_ms(step.at("t_ms"))), step.at("trips").get<bool>());
  } else if (what == "report_deadman") {
    EXPECT_EQ(p.report_deadman(), step.at("reports").get<bool>());
  } else {
    ADD_FAILURE() << "unknown step " << what;
  }
  if (step.contains("then")) expect_state(p, step.at("then"));
  return what;
}

TEST(ArmPeer, EveryCaseOfTheTableSharedWithThePythonArmSide) {
  std::ifstream in(kCases);
  ASSERT_TRUE(in) << kCases;
  const json table = json::parse(in);
  ASSERT_EQ(table.at("format"), "tactile-arm-peer-cases/1");
  const json& cases = table.at("cases");
  ASSERT_GE(cases.size(), 9U);
  std::set<std::string> done;
  for (const json& c : cases) {
    SCOPED_TRACE(c.at("name").get<std::string>());
    ArmPeer p(ns_of_ms(c.at("deadman_ms")));
    std::size_t i = 0;
    for (const json& step : c.at("steps")) {
      SCOPED_TRACE(testing::Message() << "step " << i++);
      done.insert(run_step(p, step));
    }
  }
  // Every call of ArmPeer is held to the table.
  EXPECT_EQ(done,
            (std::set<std::string>{"command", "deadman_trips", "heartbeat", "report_deadman"}));
}

}  // namespace
}  // namespace tactile::arm
