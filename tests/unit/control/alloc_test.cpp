// update() allocates nothing (docs/architecture.md, rule 4), over the paper's whole experiment
// with stale stretches, OVER and re-compressions.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "scripted_rig.hpp"
#include "tactile/control/controller.hpp"

namespace tactile::control {
namespace {

using testing::ScriptedRig;

void busy_world(ScriptedRig& rig, int& transport_frames) {
  const std::string seg = rig.segment();
  if (seg == "MOVE4") ++transport_frames;
  if (seg == "MOVE3" && rig.segment_frames() == 3) rig.slip(0, 0, 0.0, 0.012);
  if (seg == "MOVE4" && rig.segment_frames() % 5 == 0) rig.slip(1, 0, 0.0, 0.006);
  if (seg == "MOVE5" && !rig.wrist_held() && rig.wrist().position_m.z <= 0.15) {
    rig.slip(0, 0, 0.0, -0.015);
  }
  if (seg == "TURN" && rig.segments_named("TURN") == 2 && rig.segment_frames() > 30) {
    rig.slip(0, 0, 0.0, 0.01);
  }
  // The twist torque at its free-turn level, then built (the field detector's tightness rule).
  if (seg == "TURN")
    rig.twist_load(rig.segments_named("TURN") == 2 && rig.segment_frames() > 30 ? 0.2 : 0.013);
  // Counted by the script: the rig's segment clock stops while the arm holds.
  rig.set_stale(1, transport_frames > 100 && transport_frames < 103);
}

// Returns the CAP_TIGHT event's text (the rule that fired).
std::string expect_no_allocation(const Config& cfg) {
  GraspMoveTwistController ctl{cfg};
  int transport_frames = 0;
  ScriptedRig rig({}, [&transport_frames](ScriptedRig& r) { busy_world(r, transport_frames); });
  std::size_t allocations = 0;
  int updates = 0;
  std::vector<EventKind> seen;
  seen.reserve(10000);
  std::string tight_text;
  for (; updates < 20000 && !ctl.done(); ++updates) {
    const ControllerInput in = rig.next_input();
    ControllerOutput out;
    {
      tactile::testing::AllocationScope scope;
      out = ctl.update(in);
      allocations += scope.count();
    }
    for (const Event& e : out.events) {
      seen.push_back(e.kind);
      if (e.kind == EventKind::kCapTight) tight_text = e.text;
    }
    rig.apply(out);
  }
  EXPECT_EQ(allocations, 0U);
  // The run went through everything that could allocate if anything did.
  EXPECT_EQ(ctl.phase(), Phase::kDone);
  for (EventKind k : {EventKind::kRecompress, EventKind::kStaleHold, EventKind::kResumed,
                      EventKind::kCapTight, EventKind::kReleaseClassified}) {
    bool found = false;
    for (EventKind s : seen)
      found = found || s == k;
    EXPECT_TRUE(found) << to_string(k);
  }
  return tight_text;
}

TEST(Allocation, UpdateWithThePapersRuleAllocatesNothing) {
  EXPECT_EQ(expect_no_allocation(testing::paper_config()), "Ns slip detections in one cycle");
}

TEST(Allocation, UpdateWithTheFieldDetectorAllocatesNothing) {
  Config cfg;
  cfg.slip_detector = SlipDetectorKind::kField;
  // The twist torque decides before the slip count.
  EXPECT_EQ(expect_no_allocation(cfg), "twist torque stopped building");
}

TEST(Allocation, UpdateWithTheLearnedDetectorAllocatesNothing) {
  Config cfg;
  cfg.slip_detector = SlipDetectorKind::kLearned;
  expect_no_allocation(cfg);
}

TEST(Allocation, UpdateWithTheMarginGripAllocatesNothing) {
  // The margin grip's servo, friction estimate and feed-forward run on every MOVE update.
  Config cfg = testing::paper_config();
  cfg.grip = GripKind::kMargin;
  expect_no_allocation(cfg);
}

TEST(Allocation, CounterSeesAllocations) {
  // The counter itself works: otherwise the test above proves nothing.
  tactile::testing::AllocationScope scope;
  auto* v = new std::vector<int>(100);
  delete v;
  EXPECT_GE(scope.count(), 2U);
}

}  // namespace
}  // namespace tactile::control
