// The controller as a whole: start, stale data (hold, resume, continue), command arbitration,
// the end, and randomized invariants with fixed seeds: every output finite and bounded whatever
// comes in.
#include "tactile/control/controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "scripted_rig.hpp"
#include "tactile/util/random.hpp"

namespace tactile::control {
namespace {

using testing::describe;
using testing::ScriptedRig;

constexpr double kBottleTopZ = 0.15;

void bottle(ScriptedRig& rig) {
  if (rig.segment() == "MOVE5" && !rig.wrist_held() && rig.wrist().position_m.z <= kBottleTopZ) {
    rig.slip(0, 0, 0.0, -0.015);
  }
}

Config phase_one_config() {
  Config c = testing::paper_config();
  c.task = Task::kGraspMoveRelease;
  return c;
}

TEST(Controller, FirstUpdateStartsTheApproach) {
  GraspMoveTwistController ctl(phase_one_config());
  EXPECT_EQ(ctl.phase(), Phase::kIdle);
  ScriptedRig rig({}, nullptr);
  const ControllerOutput out = ctl.update(rig.next_input());
  ASSERT_EQ(out.events.size(), 1U);
  EXPECT_EQ(out.events[0].kind, EventKind::kPhase);
  EXPECT_STREQ(out.events[0].text, "APPROACH");
  EXPECT_EQ(out.command.kind, CommandKind::kMoveTo);
  EXPECT_STREQ(out.command.move_to.name, "MOVE1");
  EXPECT_EQ(out.command.move_to.segment_id, 1U);
  EXPECT_EQ(out.phase, Phase::kApproach);
  EXPECT_EQ(out.twist_cycle, 0U);
  EXPECT_FALSE(ctl.done());
}

// Stale data mid-lift: Hold once, nothing else while stale, RESUMED, the lift again under a new
// segment id, and the task carries on to the end.
TEST(Controller, StaleDataHoldsThenResumes) {
  GraspMoveTwistController ctl(phase_one_config());
  int lift_frames = 0;
  ScriptedRig rig({}, [&lift_frames](ScriptedRig& r) {
    if (r.segment() == "MOVE3") ++lift_frames;
    r.set_stale(1, lift_frames >= 10 && lift_frames < 40);
    bottle(r);
  });
  std::vector<Event> events;
  std::vector<Command> commands;
  std::vector<bool> stale_at;
  std::uint32_t lift_id = 0;
  for (int i = 0; i < 20000 && !ctl.done(); ++i) {
    const ControllerInput in = rig.next_input();
    const ControllerOutput out = ctl.update(in);
    for (const Event& e : out.events)
      events.push_back(e);
    if (out.command.kind != CommandKind::kNone) {
      commands.push_back(out.command);
      stale_at.push_back(in.fingertips[1].stale);
      if (out.command.kind == CommandKind::kMoveTo &&
          std::strcmp(out.command.move_to.name, "MOVE3") == 0 && lift_id == 0) {
        lift_id = out.command.move_to.segment_id;
      }
    }
    if (in.fingertips[1].stale) {
      // No arm motion and no squeeze while stale.
      EXPECT_TRUE(out.command.kind == CommandKind::kNone || out.command.kind == CommandKind::kHold);
      EXPECT_FALSE(out.flags.slip);
    }
    rig.apply(out);
  }
  EXPECT_EQ(ctl.phase(), Phase::kDone);
  const std::vector<std::string> expected{"PHASE APPROACH",
                                          "PHASE DESCEND",
                                          "PHASE GRASP",
                                          "TOUCH",
                                          "GRASPING_ENDED",
                                          "PHASE LIFT",
                                          "STALE_HOLD tip1",
                                          "RESUMED",
                                          "PHASE TRANSPORT",
                                          "PHASE LOWER",
                                          "RELEASE_CLASSIFIED tip0",
                                          "PHASE RELEASE",
                                          "PHASE RETRACT",
                                          "DONE"};
  EXPECT_EQ(describe(events), expected);

  // The commands around the stale stretch: Hold, then MOVE3 again with a new id.
  std::size_t hold = 0;
  while (hold < commands.size() && commands[hold].kind != CommandKind::kHold)
    ++hold;
  ASSERT_LT(hold + 1, commands.size());
  EXPECT_TRUE(stale_at[hold]);
  EXPECT_EQ(commands[hold + 1].kind, CommandKind::kMoveTo);
  EXPECT_STREQ(commands[hold + 1].move_to.name, "MOVE3");
  EXPECT_GT(commands[hold + 1].move_to.segment_id, lift_id);
  EXPECT_FALSE(stale_at[hold + 1]);
  int holds = 0;
  for (const Command& c : commands)
    holds += c.kind == CommandKind::kHold ? 1 : 0;
  EXPECT_EQ(holds, 2);  // the stale hold and the release's hold
}

// Stale holds while the fingers open for the release: each resume opens only what was left and
// the open's timer goes on, so the fingers open by open_distance_m in all (the arm follows each
// Open for the distance it names, at its speed, until a Hold stops it).
TEST(Controller, StaleHoldsDuringTheReleaseOpenNoWiderThanOneOpen) {
  const Config cfg = phase_one_config();
  GraspMoveTwistController ctl(cfg);
  ScriptedRig rig({}, [](ScriptedRig& r) { bottle(r); });
  constexpr double kDt = 0.01;  // the scripted rig's frame period
  double opened_m = 0;          // how far the fingers moved apart
  double open_left_m = 0;       // of the Open being followed
  int release_updates = 0;
  int holds_in_release = 0;
  int opens = 0;
  for (int i = 0; i < 20000 && !ctl.done(); ++i) {
    // Two updates in every four of the release stale (a loaded machine).
    const bool releasing = ctl.phase() == Phase::kRelease;
    if (releasing) ++release_updates;
    rig.set_stale(0, releasing && release_updates > 2 && release_updates % 4 < 2);
    const ControllerInput in = rig.next_input();
    const ControllerOutput out = ctl.update(in);
    if (out.command.kind == CommandKind::kOpen) {
      ++opens;
      open_left_m = out.command.open.distance_m;
      EXPECT_DOUBLE_EQ(out.command.open.speed_mps, cfg.open_speed_mps);
    } else if (out.command.kind != CommandKind::kNone) {
      if (releasing && out.command.kind == CommandKind::kHold) ++holds_in_release;
      open_left_m = 0;  // any other command stops the open
    }
    const double step = std::min(open_left_m, cfg.open_speed_mps * kDt);
    opened_m += step;
    open_left_m -= step;
    rig.apply(out);
  }
  EXPECT_EQ(ctl.phase(), Phase::kDone);
  EXPECT_GT(holds_in_release, 5);
  EXPECT_GT(opens, 5);
  EXPECT_NEAR(opened_m, cfg.open_distance_m, cfg.open_speed_mps * kDt + 1e-12);
}

TEST(Controller, StaleDuringSearchResumesTheApproach) {
  const Config cfg = phase_one_config();
  GraspMoveTwistController ctl(cfg);
  int search_frames = 0;
  ScriptedRig::Options o;
  o.initial_gap_mm = 3.0;
  ScriptedRig rig(o, [&search_frames](ScriptedRig& r) {
    if (r.segment() == "MOVE2" && r.segment_done()) ++search_frames;
    r.set_stale(0, search_frames >= 5 && search_frames < 15);
  });
  std::vector<Command> commands;
  std::vector<Event> events;
  for (int i = 0; i < 600 && rig.segment() != "MOVE3"; ++i) {
    const ControllerOutput out = ctl.update(rig.next_input());
    if (out.command.kind != CommandKind::kNone) commands.push_back(out.command);
    for (const Event& e : out.events)
      events.push_back(e);
    rig.apply(out);
  }
  // MOVE1, MOVE2, approach, Hold (stale), approach again (resumed), stop at TOUCH, MOVE3.
  ASSERT_EQ(commands.size(), 7U);
  EXPECT_EQ(commands[2].kind, CommandKind::kFingerVelocities);
  EXPECT_DOUBLE_EQ(commands[2].finger_velocities.velocity_mps[0].z, cfg.approach_speed_mps);
  EXPECT_EQ(commands[3].kind, CommandKind::kHold);
  EXPECT_EQ(commands[4].kind, CommandKind::kFingerVelocities);
  EXPECT_DOUBLE_EQ(commands[4].finger_velocities.velocity_mps[0].z, cfg.approach_speed_mps);
  EXPECT_EQ(commands[5].kind, CommandKind::kFingerVelocities);
  EXPECT_DOUBLE_EQ(commands[5].finger_velocities.velocity_mps[0].z, 0.0);
  EXPECT_EQ(commands[6].kind, CommandKind::kMoveTo);
  EXPECT_STREQ(commands[6].move_to.name, "MOVE3");
  int stale_holds = 0;
  int resumed = 0;
  for (const Event& e : events) {
    stale_holds += e.kind == EventKind::kStaleHold ? 1 : 0;
    resumed += e.kind == EventKind::kResumed ? 1 : 0;
  }
  EXPECT_EQ(stale_holds, 1);
  EXPECT_EQ(resumed, 1);
}

TEST(Controller, StaleTimeDoesNotRunTheTimers) {
  // A stale stretch longer than the search timeout during the search does not abort it.
  Config cfg = phase_one_config();
  cfg.search_timeout_s = 0.5;
  GraspMoveTwistController ctl(cfg);
  int search_frames = 0;
  ScriptedRig rig({}, [&search_frames](ScriptedRig& r) {
    if (r.segment() == "MOVE2" && r.segment_done()) ++search_frames;
    r.set_stale(0, search_frames >= 2 && search_frames < 102);  // 1 s
  });
  for (int i = 0; i < 400 && rig.segment() != "MOVE3"; ++i)
    rig.apply(ctl.update(rig.next_input()));
  EXPECT_EQ(rig.segment(), "MOVE3");
  EXPECT_NE(ctl.phase(), Phase::kAborted);
}

TEST(Controller, StaleTooLongAbortsWhenConfigured) {
  Config cfg = phase_one_config();
  cfg.stale_abort_s = 0.2;
  GraspMoveTwistController ctl(cfg);
  ScriptedRig rig({}, [](ScriptedRig& r) { r.set_stale(0, r.now() > 0.05); });
  const testing::Trace t = testing::run(ctl, rig, 1000);
  EXPECT_EQ(ctl.phase(), Phase::kAborted);
  ASSERT_FALSE(t.events.empty());
  EXPECT_EQ(t.events.back().kind, EventKind::kAborted);
  EXPECT_EQ(t.commands.back().kind, CommandKind::kStop);
  EXPECT_NEAR(rig.now(), 0.06 + 0.2, 0.03);
}

// The margin grip through a stale hold in the carry: the hold stops the fingers but is no new
// grasp, so the grip's target after RESUMED is the one before the hold (a grip started again from
// grip_min_n opened on the carried cap: docs/control.md, "A stall it did not survive").
TEST(Controller, AStaleHoldKeepsTheMarginGripsTarget) {
  Config cfg = phase_one_config();
  cfg.grip = GripKind::kMargin;
  GraspMoveTwistController ctl(cfg);
  int carry_frames = 0;
  ScriptedRig rig({}, [&carry_frames](ScriptedRig& r) {
    if (r.segment() == "MOVE4") ++carry_frames;
    // A load early in the carry raises the target; gone, the target relaxes toward the least.
    r.twist_load(carry_frames > 0 && carry_frames < 10 ? 0.02 : 0.0);
    r.set_stale(1, carry_frames >= 20 && carry_frames < 50);
    bottle(r);
  });
  double before = 0, after = 0;
  bool was_stale = false;
  for (int i = 0; i < 20000 && !ctl.done(); ++i) {
    const ControllerInput in = rig.next_input();
    const bool stale = in.fingertips[1].stale;
    if (stale && !was_stale) before = ctl.finger_speeds().grip_law().target_n();
    const ControllerOutput out = ctl.update(in);
    if (!stale && was_stale) after = ctl.finger_speeds().grip_law().target_n();
    was_stale = stale;
    rig.apply(out);
  }
  EXPECT_EQ(ctl.phase(), Phase::kDone);
  ASSERT_GT(before, 1.2 * cfg.grip_min_n) << "relaxing from the load's target";
  EXPECT_GE(after, before) << "RESUMED with the target before the hold";
}

TEST(Controller, StaleHoldsForEverByDefault) {
  GraspMoveTwistController ctl(phase_one_config());
  ScriptedRig rig({}, [](ScriptedRig& r) { r.set_stale(1, r.now() > 0.05); });
  const testing::Trace t = testing::run(ctl, rig, 3000);  // 30 s
  EXPECT_FALSE(ctl.done());
  EXPECT_EQ(t.events.back().kind, EventKind::kStaleHold);
  EXPECT_EQ(t.commands.back().kind, CommandKind::kHold);
}

TEST(Controller, StaleFromTheStartHoldsThenStarts) {
  GraspMoveTwistController ctl(phase_one_config());
  ScriptedRig rig({}, [](ScriptedRig& r) { r.set_stale(0, r.now() < 0.05); });
  const testing::Trace t = testing::run(ctl, rig, 10);
  ASSERT_GE(t.events.size(), 3U);
  EXPECT_EQ(describe(t.events[0]), "STALE_HOLD tip0");
  EXPECT_EQ(describe(t.events[1]), "RESUMED");
  EXPECT_EQ(describe(t.events[2]), "PHASE APPROACH");
  EXPECT_EQ(t.commands[0].kind, CommandKind::kHold);
  EXPECT_EQ(t.commands[1].kind, CommandKind::kMoveTo);
}

TEST(Controller, FingerVelocitiesAreSentOnlyWhenTheyChange) {
  GraspMoveTwistController ctl{testing::paper_config()};
  ScriptedRig rig({}, [](ScriptedRig& r) {
    if (r.segment() == "MOVE4" && r.segment_frames() % 7 == 0) r.slip(0, 0, 0, 0.01);
    bottle(r);
  });
  const testing::Trace t = testing::run(ctl, rig);
  const FingerVelocities* last = nullptr;
  int sent = 0;
  for (const Command& c : t.commands) {
    if (c.kind != CommandKind::kFingerVelocities) {
      // Hold, Open, Stop and a MoveTo that drops the fingers leave them still.
      if (c.kind != CommandKind::kMoveTo || !c.move_to.keep_finger_velocities) last = nullptr;
      continue;
    }
    ++sent;
    if (last != nullptr) {
      bool differs = false;
      for (std::size_t f = 0; f < kFingertips; ++f) {
        differs = differs || norm(c.finger_velocities.velocity_mps[f] - last->velocity_mps[f]) > 0;
      }
      EXPECT_TRUE(differs) << "repeated finger velocities";
    }
    last = &c.finger_velocities;
  }
  EXPECT_GT(sent, 10);
}

TEST(Controller, NothingAfterTheEnd) {
  GraspMoveTwistController ctl(phase_one_config());
  ScriptedRig rig({}, bottle);
  testing::run(ctl, rig);
  ASSERT_TRUE(ctl.done());
  for (int i = 0; i < 20; ++i) {
    ControllerInput in = rig.next_input();
    in.fingertips[0].stale = i % 2 == 0;
    const ControllerOutput out = ctl.update(in);
    EXPECT_EQ(out.command.kind, CommandKind::kNone);
    EXPECT_TRUE(out.events.empty());
    EXPECT_EQ(out.phase, Phase::kDone);
  }
}

TEST(Controller, OverDuringTheGraspBacksOffAndIsReported) {
  const Config cfg = phase_one_config();
  GraspMoveTwistController ctl(cfg);
  // Something pushes the cap into fingertip 0 while the grasp settles.
  ScriptedRig rig({}, nullptr);
  bool over_seen = false;
  bool backed_off = false;
  for (int i = 0; i < 600 && !over_seen; ++i) {
    ControllerInput in = rig.next_input();
    std::array<ElementReading, testing::kElements> pressed{};
    if (ctl.phase() == Phase::kGrasp && rig.in_contact(0) && rig.in_contact(1)) {
      pressed[0].contact = true;
      pressed[0].fz = 2.8;
      pressed[0].id = 10;
      in.fingertips[0].elements = pressed;
    }
    const ControllerOutput out = ctl.update(in);
    for (const Event& e : out.events) {
      if (e.kind == EventKind::kOver) {
        over_seen = true;
        EXPECT_EQ(e.fingertip, 0);
        EXPECT_DOUBLE_EQ(e.value, 2.8);
        EXPECT_EQ(e.element_id, 10U);
      }
    }
    if (out.command.kind == CommandKind::kFingerVelocities &&
        out.command.finger_velocities.velocity_mps[0].z < 0) {
      backed_off = true;
      EXPECT_DOUBLE_EQ(out.command.finger_velocities.velocity_mps[0].z, -cfg.backoff_speed_mps);
    }
    rig.apply(out);
  }
  EXPECT_TRUE(over_seen);
  EXPECT_TRUE(backed_off);
}

TEST(Controller, EventsNameTheirStep) {
  GraspMoveTwistController ctl(phase_one_config());
  ScriptedRig rig({}, [](ScriptedRig& r) {
    if (r.segment() == "MOVE3" && r.segment_frames() == 3) r.slip(0, 0, 0, 0.01);
    bottle(r);
  });
  const testing::Trace t = testing::run(ctl, rig);
  for (const Event& e : t.events) {
    switch (e.kind) {
      case EventKind::kTouch:
      case EventKind::kGraspingEnded:
        EXPECT_EQ(e.phase, Phase::kGrasp);
        break;
      case EventKind::kGraspClassified:
        EXPECT_EQ(e.phase, Phase::kLift);
        break;
      case EventKind::kReleaseClassified:
        EXPECT_EQ(e.phase, Phase::kLower);
        break;
      case EventKind::kPhase:
        EXPECT_STREQ(e.text, to_string(e.phase));
        break;
      default:
        break;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Randomized invariants.

double wild(util::Random& rng) {
  switch (rng.below(12)) {
    case 0:
      return std::numeric_limits<double>::quiet_NaN();
    case 1:
      return std::numeric_limits<double>::infinity();
    case 2:
      return -std::numeric_limits<double>::infinity();
    case 3:
      return rng.uniform(-1e300, 1e300);
    case 4:
      return 0.0;
    default:
      return rng.normal(0.0, 1.0);
  }
}

void expect_finite(const Command& c, const Config& cfg, bool placed, const std::string& where) {
  switch (c.kind) {
    case CommandKind::kMoveTo: {
      const MoveTo& m = c.move_to;
      EXPECT_TRUE(is_finite(m.target.position_m) && std::isfinite(m.target.yaw_rad)) << where;
      EXPECT_GT(m.max_speed_mps, 0.0) << where;
      EXPECT_LE(m.max_speed_mps, cfg.move_speed_mps) << where;
      EXPECT_GT(m.max_yaw_rate_rps, 0.0) << where;
      EXPECT_LE(m.max_yaw_rate_rps, std::max(cfg.max_yaw_rate_rps, cfg.twist_yaw_rate_rps))
          << where;
      EXPECT_NE(m.name, nullptr);
      if (placed) {
        // Every target of a placed task lies in the box the configuration spans.
        const Vec3 p = m.target.position_m;
        EXPECT_GE(p.z, cfg.lower_limit_m) << where;
        EXPECT_LE(p.z, std::max(cfg.safe_height_m, cfg.carry_height_m) + cfg.retract_height_m)
            << where;
        EXPECT_GE(p.x, std::min(cfg.cap_x_m, cfg.bottle_x_m)) << where;
        EXPECT_LE(p.x, std::max(cfg.cap_x_m, cfg.bottle_x_m)) << where;
        EXPECT_GE(p.y, std::min(cfg.cap_y_m, cfg.bottle_y_m)) << where;
        EXPECT_LE(p.y, std::max(cfg.cap_y_m, cfg.bottle_y_m)) << where;
        EXPECT_LE(std::abs(m.target.yaw_rad - cfg.grasp_yaw_rad), cfg.twist_angle_rad + 1e-12)
            << where;
      }
      break;
    }
    case CommandKind::kFingerVelocities:
      for (const Vec3& v : c.finger_velocities.velocity_mps) {
        EXPECT_TRUE(is_finite(v)) << where;
        EXPECT_LE(norm(v), cfg.max_finger_speed_mps * (1 + 1e-12)) << where;
      }
      break;
    case CommandKind::kOpen:
      EXPECT_DOUBLE_EQ(c.open.speed_mps, cfg.open_speed_mps) << where;
      // The whole stroke, or after a stale hold what was left of it.
      EXPECT_GT(c.open.distance_m, 0.0) << where;
      EXPECT_LE(c.open.distance_m, cfg.open_distance_m) << where;
      break;
    default:
      break;
  }
}

void expect_sane(const ControllerOutput& out, const Config& cfg, bool placed,
                 const std::string& where) {
  expect_finite(out.command, cfg, placed, where);
  EXPECT_EQ(out.events.dropped(), 0U) << where;
  for (const Event& e : out.events) {
    EXPECT_TRUE(std::isfinite(e.value)) << where;
    EXPECT_NE(e.text, nullptr) << where;
    EXPECT_GE(e.fingertip, kNoFingertip) << where;
    EXPECT_LT(e.fingertip, static_cast<int>(kFingertips)) << where;
  }
  for (const FingertipFlags& f : out.flags.fingertip) {
    EXPECT_TRUE(std::isfinite(f.max_fz_n) && std::isfinite(f.max_slip_mm)) << where;
    EXPECT_EQ(f.touch, f.touch || f.slip) << where;
  }
  EXPECT_LE(out.twist_cycle, cfg.max_twist_cycles) << where;
}

// Anything at all comes in: readings, normals, arm feedback and clock garbage included.
TEST(ControllerRandomized, GarbageInFiniteAndBoundedOut) {
  for (std::uint64_t seed : {1U, 2U, 3U, 4U, 5U, 6U, 7U, 8U}) {
    util::Random rng(seed);
    Config cfg = testing::paper_config();
    cfg.task = static_cast<Task>(seed % 3);
    cfg.search_timeout_s = 0.2;
    cfg.segment_timeout_s = 0.5;
    cfg.grasp_settle_s = 0.0;
    const bool placed = cfg.task != Task::kTwistOnly;
    GraspMoveTwistController ctl(cfg);
    std::array<std::array<ElementReading, 8>, kFingertips> elems{};
    std::array<std::array<Vec3, 8>, kFingertips> normals{};
    double now = 0;
    std::uint32_t last_segment = 0;
    for (int i = 0; i < 4000; ++i) {
      ControllerInput in;
      for (std::size_t f = 0; f < kFingertips; ++f) {
        const std::size_t n = rng.below(9);
        for (std::size_t e = 0; e < n; ++e) {
          ElementReading& r = elems[f][e];
          r.id = static_cast<std::uint32_t>(rng.next());
          r.contact = rng.below(4) != 0;
          r.has_displacement = rng.below(3) != 0;
          r.fz = rng.below(2) != 0 ? rng.uniform(0.0, 3.5) : wild(rng);
          r.dx_mm = rng.below(2) != 0 ? rng.normal(0.0, 0.006) : wild(rng);
          r.dy_mm = rng.below(2) != 0 ? rng.normal(0.0, 0.006) : wild(rng);
          normals[f][e] = rng.below(3) != 0 ? Vec3{0, 0, 1} : Vec3{wild(rng), wild(rng), wild(rng)};
        }
        in.fingertips[f].elements = std::span<const ElementReading>(elems[f].data(), n);
        in.fingertips[f].normals = std::span<const Vec3>(normals[f].data(), rng.below(9));
        in.fingertips[f].fresh = rng.below(4) != 0;
        in.fingertips[f].stale = rng.below(40) == 0;
      }
      in.arm.wrist = {{wild(rng), wild(rng), wild(rng)}, wild(rng)};
      in.arm.active_segment_id =
          rng.below(2) != 0 ? last_segment : static_cast<std::uint32_t>(rng.next());
      in.arm.segment_done = rng.below(3) == 0;
      in.arm.holding = rng.below(2) == 0;
      now += rng.below(50) == 0 ? wild(rng) : 0.01;
      in.now_s = now;
      const ControllerOutput out = ctl.update(in);
      const std::string where = "seed " + std::to_string(seed) + " update " + std::to_string(i);
      expect_sane(out, cfg, placed, where);
      if (in.fingertips[0].stale || in.fingertips[1].stale) {
        EXPECT_TRUE(out.command.kind == CommandKind::kNone ||
                    out.command.kind == CommandKind::kHold ||
                    out.command.kind == CommandKind::kStop)
            << where;
      }
      if (out.command.kind == CommandKind::kMoveTo) last_segment = out.command.move_to.segment_id;
      if (::testing::Test::HasFailure()) return;
    }
  }
}

// A plausible world with random slips everywhere: the sequence always ends, its grammar holds,
// and every output is finite and bounded.
TEST(ControllerRandomized, RandomSlipsKeepTheSequenceWellFormed) {
  for (std::uint64_t seed = 11; seed < 31; ++seed) {
    util::Random rng(seed);
    Config cfg = testing::paper_config();
    cfg.task = seed % 2 == 0 ? Task::kGraspMoveTwist : Task::kTwistOnly;
    cfg.max_twist_cycles = 4;
    const double p = rng.uniform(0.0, 0.2);  // slip probability per element and frame
    ScriptedRig::Options o;
    o.start = {{cfg.bottle_x_m, cfg.bottle_y_m, kBottleTopZ}, 0.0};
    if (cfg.task == Task::kGraspMoveTwist) o.start = {{cfg.cap_x_m, cfg.cap_y_m, 0.25}, 0.0};
    o.stiffness_n_per_mm = rng.uniform(0.5, 5.0);
    ScriptedRig rig(o, [&rng, p](ScriptedRig& r) {
      for (std::size_t f = 0; f < kFingertips; ++f) {
        for (std::size_t e = 0; e < testing::kElements; ++e) {
          if (rng.uniform() < p) r.slip(f, e, rng.normal(0, 0.006), rng.normal(0, 0.006));
        }
        r.set_stale(f, rng.below(200) == 0);
      }
      bottle(r);
    });
    GraspMoveTwistController ctl(cfg);
    std::vector<Event> events;
    int i = 0;
    for (; i < 40000 && !ctl.done(); ++i) {
      const ControllerOutput out = ctl.update(rig.next_input());
      expect_sane(out, cfg, cfg.task != Task::kTwistOnly, "seed " + std::to_string(seed));
      for (const Event& e : out.events)
        events.push_back(e);
      rig.apply(out);
    }
    const std::string where = "seed " + std::to_string(seed);
    EXPECT_TRUE(ctl.done()) << where;
    ASSERT_FALSE(events.empty()) << where;
    const EventKind last = events.back().kind;
    EXPECT_TRUE(last == EventKind::kDone || last == EventKind::kAborted) << where;
    int ends = 0;
    int tight = 0;
    int grasp = 0;
    int release = 0;
    std::uint32_t cycle = 0;
    for (const Event& e : events) {
      ends += e.kind == EventKind::kDone || e.kind == EventKind::kAborted ? 1 : 0;
      tight += e.kind == EventKind::kCapTight ? 1 : 0;
      grasp += e.kind == EventKind::kGraspClassified ? 1 : 0;
      release += e.kind == EventKind::kReleaseClassified ? 1 : 0;
      if (e.kind == EventKind::kTwistCycle) {
        EXPECT_EQ(e.cycle, cycle + 1) << where;
        cycle = e.cycle;
      }
      if (e.kind == EventKind::kCapTight) {
        EXPECT_EQ(e.cycle, cycle) << where;
      }
      if (e.kind == EventKind::kGraspClassified) {
        EXPECT_EQ(e.phase, Phase::kLift) << where;
      }
      if (e.kind == EventKind::kReleaseClassified) {
        EXPECT_EQ(e.phase, Phase::kLower) << where;
      }
    }
    EXPECT_EQ(ends, 1) << where;
    EXPECT_LE(tight, 1) << where;
    EXPECT_LE(grasp, 1) << where;
    EXPECT_LE(release, 1) << where;
    EXPECT_LE(cycle, cfg.max_twist_cycles) << where;
    if (::testing::Test::HasFailure()) return;
  }
}

}  // namespace
}  // namespace tactile::control
