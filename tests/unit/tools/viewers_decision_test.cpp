// Every viewer shows the decision hand_node made (docs/architecture.md, rule 15): one stream in
// which the paper's rule and hand_node's detector disagree, fed to tactile_live's model,
// tactile_web's update and tactile_plot's data. Element 7 moves ten times dr in every frame while
// hand_node's Decision says it does not slip; element 12 barely moves while the Decision marks it
// slipping. Each viewer must draw hand_node's flags and elements, name its detector, say so when
// there is no Decision, and recompute only when asked.
#include <gtest/gtest.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dashboard.hpp"
#include "plot_data.hpp"
#include "snapshot.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile {
namespace {

constexpr std::uint32_t kMoving = 7;   // moves 0.04 mm a frame: the paper's rule says slip
constexpr std::uint32_t kMarked = 12;  // moves 0.0001 mm: hand_node's detector says slip
constexpr std::uint64_t kFrames = 6;

struct Message {
  std::string topic;
  std::string payload;
};

std::string frame(std::uint64_t sequence) {
  v1::Envelope env;
  auto* f = env.mutable_tactile_frame();
  f->set_sensor_id("left");
  f->set_sequence(sequence);
  f->set_status(v1::FRAME_STATUS_COMPLETE);
  for (std::uint32_t e = 0; e < 41; ++e) {
    auto* r = f->add_elements();
    r->set_id(e);
    if (e == kMoving || e == kMarked) {
      r->set_contact(true);
      r->set_fz_n(0.3);  // below F1: TOUCH only where something slips
      r->set_has_displacement(sequence > 0);
      r->set_dy_mm(e == kMoving ? 0.04 : 0.0001);
    }
  }
  std::string out;
  wire::encode(env, out);
  return out;
}

// hand_node's Decision on frame `sequence`: element 12 slips (or, with `slip` false, nothing).
std::string decision(std::uint64_t sequence, bool slip) {
  v1::Envelope env;
  auto* d = env.mutable_decision();
  d->set_phase("TRANSPORT");
  d->set_slip_detector("learned");
  auto* a = d->add_answers();
  a->set_sensor_id("left");
  a->set_sequence(sequence);
  auto* t = d->add_fingertips();
  t->set_sensor_id("left");
  t->set_slip(slip);
  t->set_touch(slip);
  t->set_max_fz_n(0.3);
  if (slip) {
    t->set_slipping_elements(1);
    t->add_slipping_element_ids(kMarked);
  }
  std::string out;
  wire::encode(env, out);
  return out;
}

// Frames 0 to 5, each followed by hand_node's decision on it: slip on frame 5 only (element 12).
std::vector<Message> stream(bool with_decisions) {
  std::vector<Message> out;
  for (std::uint64_t k = 0; k < kFrames; ++k) {
    out.push_back({wire::frame_topic("left"), frame(k)});
    if (with_decisions) out.push_back({wire::kDecisionTopic, decision(k, k == kFrames - 1)});
  }
  return out;
}

// The model after the messages (held by pointer: it does not move).
std::unique_ptr<live::LiveModel> live_model(
    const std::vector<Message>& messages,
    std::optional<control::SlipDetectorKind> recompute = std::nullopt) {
  auto model =
      std::make_unique<live::LiveModel>(live::ModelOptions{control::Config{}, 8, recompute});
  live::LiveModel& m = *model;
  std::int64_t now = 1'000'000'000;
  for (const auto& msg : messages) {
    m.add(msg.topic, wire::bytes_of(msg.payload), now);
    now += 5'000'000;
  }
  m.tick(now, 1'763'700'000'000'000'000);
  return model;
}

plots::PlotData plot_data(const std::vector<Message>& messages,
                          std::optional<control::SlipDetectorKind> recompute = std::nullopt) {
  plots::PlotOptions o;
  o.recompute = recompute;
  plots::PlotData d(o);
  std::int64_t now = 1'000'000'000;
  for (const auto& msg : messages) {
    v1::LogRecord r;
    r.set_receive_time_ns(now);
    r.set_topic(msg.topic);
    r.set_kind(v1::PAYLOAD_KIND_ENVELOPE);
    r.set_payload(msg.payload);
    d.add(r);
    now += 5'000'000;
  }
  d.finish();
  return d;
}

nlohmann::json web_update(const std::unique_ptr<live::LiveModel>& m) {
  web::SnapshotWriter w({}, control::Config{});
  std::string out;
  w.write(m->state(), {1, 0, 1}, out);
  return nlohmann::json::parse(out);
}

// The paper's rule on this stream: element 7 slips, element 12 does not (the premise).
TEST(ViewersShowHandNodesDecision, ThePapersRuleDisagreesWithHandNode) {
  const auto paper = live_model(stream(false), control::SlipDetectorKind::kPaper);
  const live::FingertipView& f = paper->state().fingertips.at(0);
  EXPECT_TRUE(f.slip);
  EXPECT_TRUE(f.elements[kMoving].slip);
  EXPECT_FALSE(f.elements[kMarked].slip);
}

TEST(ViewersShowHandNodesDecision, TactileLive) {
  const auto m = live_model(stream(true));
  const live::LiveState& s = m->state();
  ASSERT_EQ(s.fingertips.size(), 1U);
  const live::FingertipView& f = s.fingertips[0];
  EXPECT_TRUE(f.decided);
  EXPECT_TRUE(f.slip);
  EXPECT_TRUE(f.touch);
  EXPECT_FALSE(f.elements[kMoving].slip) << "hand_node decided element 7 does not slip";
  EXPECT_TRUE(f.elements[kMarked].slip) << "hand_node decided element 12 slips";
  EXPECT_EQ(s.flags_from, live::FlagSource::kHandNode);
  EXPECT_EQ(s.detector, "learned");
  const std::string screen = live::render(s, {}, {100, 40, false, 2.5});
  EXPECT_NE(screen.find("flags: hand_node (learned)"), std::string::npos) << screen;
  EXPECT_NE(live::summary_lines(s).find("flags=TOUCH,SLIP slipping=12 by=hand_node "
                                        "detector=learned"),
            std::string::npos)
      << live::summary_lines(s);

  // A frame after the decision keeps hand_node's marks, not the paper's rule.
  std::vector<Message> more = stream(true);
  more.push_back({wire::frame_topic("left"), frame(kFrames)});
  const auto after = live_model(more);
  const live::FingertipView& g = after->state().fingertips[0];
  EXPECT_FALSE(g.elements[kMoving].slip);
  EXPECT_TRUE(g.elements[kMarked].slip);
}

TEST(ViewersShowHandNodesDecision, TactileWeb) {
  const nlohmann::json j = web_update(live_model(stream(true)));
  EXPECT_EQ(j["flags_from"], "hand_node");
  EXPECT_EQ(j["detector"], "learned");
  EXPECT_EQ(j["flags_label"], "flags: hand_node (learned)");
  const auto& f = j["fingertips"][0];
  EXPECT_EQ(f["decided"], true);
  EXPECT_EQ(f["slip"], true);
  EXPECT_EQ(f["elements"][kMoving]["slip"], false);
  EXPECT_EQ(f["elements"][kMarked]["slip"], true);
}

TEST(ViewersShowHandNodesDecision, TactilePlot) {
  const plots::PlotData d = plot_data(stream(true));
  EXPECT_EQ(d.flag_source(), plots::FlagSource::kHandNode);
  EXPECT_EQ(d.flag_source_text(), "flags: hand_node (learned)");
  ASSERT_EQ(d.sensors().size(), 1U);
  const auto& frames = d.sensors()[0].frames;
  ASSERT_EQ(frames.size(), kFrames);
  for (std::uint64_t k = 0; k < kFrames; ++k) {
    SCOPED_TRACE(k);
    EXPECT_TRUE(frames[k].decided);
    // The paper's rule would say slip on every frame after the first.
    EXPECT_EQ(frames[k].slip, k == kFrames - 1);
    EXPECT_EQ(frames[k].touch, k == kFrames - 1);
  }
}

// No Decision in the stream: no viewer shows flags, and each says so; asked, each recomputes
// with the control core's detector and says that.
TEST(ViewersShowHandNodesDecision, WithoutDecisionsEachSaysSoAndRecomputesOnlyWhenAsked) {
  const auto m = live_model(stream(false));
  const live::FingertipView& f = m->state().fingertips.at(0);
  EXPECT_FALSE(f.decided);
  EXPECT_FALSE(f.slip);
  EXPECT_FALSE(f.elements[kMoving].slip);
  const std::string screen = live::render(m->state(), {}, {100, 40, false, 2.5});
  EXPECT_NE(screen.find("flags: no decisions from hand_node"), std::string::npos) << screen;
  EXPECT_NE(screen.find("no decision"), std::string::npos);
  const nlohmann::json j = web_update(m);
  EXPECT_EQ(j["flags_from"], "none");
  EXPECT_EQ(j["fingertips"][0]["decided"], false);
  const plots::PlotData d = plot_data(stream(false));
  EXPECT_EQ(d.flag_source(), plots::FlagSource::kNone);
  EXPECT_NE(d.flag_source_text().find("no hand_node decisions"), std::string::npos);
  for (const auto& x : d.sensors()[0].frames)
    EXPECT_FALSE(x.slip || x.decided);

  // --recompute paper: the paper's rule, labelled as recomputed, even beside hand_node's.
  const auto r = live_model(stream(true), control::SlipDetectorKind::kPaper);
  EXPECT_EQ(r->state().flags_from, live::FlagSource::kRecomputed);
  EXPECT_TRUE(r->state().fingertips[0].elements[kMoving].slip);
  EXPECT_FALSE(r->state().fingertips[0].elements[kMarked].slip);
  EXPECT_EQ(web_update(r)["flags_label"], "flags: recomputed (paper)");
  const plots::PlotData rd = plot_data(stream(true), control::SlipDetectorKind::kPaper);
  EXPECT_EQ(rd.flag_source_text(), "flags: recomputed (paper)");
  EXPECT_TRUE(rd.sensors()[0].frames[1].slip);
}

}  // namespace
}  // namespace tactile
