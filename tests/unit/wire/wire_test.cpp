// Wire conversions (pure) and the ZeroMQ endpoints over real sockets.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <thread>

#include "synthetic.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::wire {
namespace {

using namespace std::chrono_literals;

Calibration three_elements() {
  testing::SceneOptions o;
  o.width = 96;
  o.height = 64;
  return testing::grid_calibration(o, 3, 1, 30, 12);
}

std::vector<ElementReading> readings_for(const Calibration& cal) {
  std::vector<ElementReading> r(cal.elements.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    r[i].id = cal.elements[i].id;
    r[i].G = 100.0 * static_cast<double>(i);
  }
  r[1].contact = true;
  r[1].has_displacement = true;
  r[1].G = 5321;
  r[1].x_px = 47.25;
  r[1].y_px = 31.5;
  r[1].dx_mm = 0.005;
  r[1].dy_mm = -0.0025;
  r[1].ux_mm = 0.01;
  r[1].uy_mm = -0.02;
  r[1].fx = 0.025;
  r[1].fy = -0.05;
  r[1].fz = 0.53;
  return r;
}

FrameHeader header(v1::FrameStatus status = v1::FRAME_STATUS_COMPLETE) {
  FrameHeader h;
  h.sequence = 42;
  h.camera_frame_id = 65535;
  h.camera_timestamp_ns = 1'700'000'000'123'456'789;
  h.receive_timestamp_ns = h.camera_timestamp_ns + 400'000;
  h.publish_timestamp_ns = h.receive_timestamp_ns + 30'000;
  h.status = status;
  h.nominal_period_ns = 10'000'000;
  h.frames_skipped = 1;
  h.measure_time_us = 12.5;
  return h;
}

TEST(Envelope, RoundTrip) {
  const Calibration cal = three_elements();
  v1::Envelope env;
  fill_tactile_frame("left", header(), readings_for(cal), cal.mm_per_px,
                     *env.mutable_tactile_frame());
  std::string bytes;
  encode(env, bytes);
  v1::Envelope back;
  ASSERT_EQ(decode(bytes_of(bytes), back), DecodeStatus::kOk);
  EXPECT_EQ(back.schema_version(), kSchemaVersion);
  ASSERT_TRUE(back.has_tactile_frame());
  EXPECT_EQ(back.tactile_frame().sensor_id(), "left");
  EXPECT_EQ(back.tactile_frame().elements_size(), 3);
}

TEST(Envelope, RefusesWhatItCannotTrust) {
  v1::Envelope env;
  env.mutable_heartbeat()->set_time_ns(5);
  std::string bytes;
  encode(env, bytes);
  env.set_schema_version(2);
  std::string v2;
  env.SerializeToString(&v2);
  v1::Envelope out;
  EXPECT_EQ(decode(bytes_of(v2), out), DecodeStatus::kWrongVersion);
  EXPECT_EQ(decode(bytes_of(std::string("\xff\xff\xff\xff garbage", 12)), out),
            DecodeStatus::kMalformed);
  EXPECT_EQ(decode(bytes_of(bytes.substr(0, bytes.size() - 1)), out), DecodeStatus::kMalformed);
  v1::Envelope empty;
  std::string empty_bytes;
  encode(empty, empty_bytes);
  EXPECT_EQ(decode(bytes_of(empty_bytes), out), DecodeStatus::kEmpty);
  EXPECT_EQ(decode(bytes_of(std::string(kMaxMessageBytes + 1, '\0')), out),
            DecodeStatus::kTooLarge);
  EXPECT_EQ(decode(bytes_of(bytes), out), DecodeStatus::kOk);
}

TEST(TactileFrame, ReadingsSurviveTheWire) {
  const Calibration cal = three_elements();
  const auto readings = readings_for(cal);
  v1::TactileFrame msg;
  fill_tactile_frame("left", header(), readings, cal.mm_per_px, msg);
  EXPECT_DOUBLE_EQ(msg.elements(1).x_mm(), 47.25 * cal.mm_per_px);
  EXPECT_EQ(msg.elements(0).x_mm(), 0.0);  // out of contact: no centroid
  ReceivedFrame got;
  ASSERT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kOk);
  EXPECT_EQ(got.header.sequence, 42U);
  EXPECT_EQ(got.header.camera_frame_id, 65535U);
  EXPECT_EQ(got.header.camera_timestamp_ns, header().camera_timestamp_ns);
  EXPECT_EQ(got.header.frames_skipped, 1U);
  ASSERT_EQ(got.elements.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    const ElementReading& a = readings[i];
    const ElementReading& b = got.elements[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.contact, b.contact);
    EXPECT_EQ(a.has_displacement, b.has_displacement);
    EXPECT_DOUBLE_EQ(a.G, b.G);
    EXPECT_NEAR(a.x_px, b.x_px, 1e-9);
    EXPECT_NEAR(a.y_px, b.y_px, 1e-9);
    EXPECT_DOUBLE_EQ(a.dx_mm, b.dx_mm);
    EXPECT_DOUBLE_EQ(a.dy_mm, b.dy_mm);
    EXPECT_DOUBLE_EQ(a.ux_mm, b.ux_mm);
    EXPECT_DOUBLE_EQ(a.uy_mm, b.uy_mm);
    EXPECT_DOUBLE_EQ(a.fx, b.fx);
    EXPECT_DOUBLE_EQ(a.fy, b.fy);
    EXPECT_DOUBLE_EQ(a.fz, b.fz);
  }
}

TEST(TactileFrame, IncompleteFramesCarryNoReadings) {
  const Calibration cal = three_elements();
  v1::TactileFrame msg;
  fill_tactile_frame("left", header(), readings_for(cal), cal.mm_per_px, msg);
  ASSERT_EQ(msg.elements_size(), 3);
  fill_tactile_frame("left", header(v1::FRAME_STATUS_MISSING_PACKETS), readings_for(cal),
                     cal.mm_per_px, msg);
  EXPECT_EQ(msg.elements_size(), 0);
  ReceivedFrame got;
  EXPECT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kOk);
  EXPECT_EQ(got.header.status, v1::FRAME_STATUS_MISSING_PACKETS);
  // An incomplete frame that claims readings is not to be trusted.
  msg.add_elements()->set_id(0);
  EXPECT_EQ(read_tactile_frame(msg, cal, got), DecodeStatus::kInvalid);
}

TEST(TactileFrame, RefusesFramesThatDoNotMatchTheCalibration) {
  const Calibration cal = three_elements();
  const auto readings = readings_for(cal);
  ReceivedFrame got;
  const auto fresh = [&] {
    v1::TactileFrame m;
    fill_tactile_frame("left", header(), readings, cal.mm_per_px, m);
    return m;
  };
  v1::TactileFrame m = fresh();
  m.mutable_elements()->RemoveLast();
  EXPECT_EQ(read_tactile_frame(m, cal, got), DecodeStatus::kInvalid) << "too few";
  m = fresh();
  m.mutable_elements(0)->set_id(7);
  EXPECT_EQ(read_tactile_frame(m, cal, got), DecodeStatus::kInvalid) << "wrong id";
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    m = fresh();
    m.mutable_elements(1)->set_fz_n(bad);
    EXPECT_EQ(read_tactile_frame(m, cal, got), DecodeStatus::kInvalid) << "non-finite";
    m = fresh();
    m.mutable_elements(2)->set_dy_mm(bad);
    EXPECT_EQ(read_tactile_frame(m, cal, got), DecodeStatus::kInvalid) << "non-finite";
  }
  m = fresh();
  m.mutable_elements(1)->set_g(-1);
  EXPECT_EQ(read_tactile_frame(m, cal, got), DecodeStatus::kInvalid) << "negative G";
  m = fresh();
  m.set_status(static_cast<v1::FrameStatus>(99));
  EXPECT_EQ(read_tactile_frame(m, cal, got), DecodeStatus::kInvalid) << "unknown status";
}

// --- arm link and events ------------------------------------------------------------------

const FingertipIds kIds{"left", "right"};

control::Command round_trip(const control::Command& c, ReceivedCommand& got,
                            DecodeStatus want = DecodeStatus::kOk) {
  Answers answers;
  answers.add({0, 17, 1000});
  answers.add({1, 18, 2000});
  v1::ArmCommand msg;
  fill_arm_command(c, 9, 123, answers, kIds, msg);
  EXPECT_EQ(msg.answers_size(), 2);
  EXPECT_EQ(msg.answers(1).sensor_id(), "right");
  EXPECT_EQ(read_arm_command(msg, kIds, got), want);
  EXPECT_EQ(got.sequence, 9U);
  EXPECT_EQ(got.send_timestamp_ns, 123);
  EXPECT_EQ(got.answers.count, 2U);
  EXPECT_EQ(got.answers.refs[1].fingertip, 1);
  EXPECT_EQ(got.answers.refs[1].sequence, 18U);
  return got.command;
}

TEST(ArmCommand, EveryKindSurvivesTheWire) {
  ReceivedCommand got;
  control::MoveTo m;
  m.segment_id = 4;
  m.name = "MOVE4";
  m.target = {{0.35, 0.1, 0.25}, -0.5};
  m.max_speed_mps = 0.08;
  m.max_yaw_rate_rps = 1.0;
  m.keep_finger_velocities = true;
  control::Command c = round_trip(control::Command::move(m), got);
  ASSERT_EQ(c.kind, control::CommandKind::kMoveTo);
  EXPECT_EQ(c.move_to.segment_id, 4U);
  EXPECT_STREQ(c.move_to.name, "MOVE4");
  EXPECT_DOUBLE_EQ(c.move_to.target.position_m.y, 0.1);
  EXPECT_DOUBLE_EQ(c.move_to.target.yaw_rad, -0.5);
  EXPECT_TRUE(c.move_to.keep_finger_velocities);

  control::FingerVelocities v;
  v.velocity_mps = {Vec3{0.001, -0.002, 0.005}, Vec3{0, 0, 0.004}};
  c = round_trip(control::Command::velocities(v), got);
  ASSERT_EQ(c.kind, control::CommandKind::kFingerVelocities);
  EXPECT_DOUBLE_EQ(c.finger_velocities.velocity_mps[0].y, -0.002);
  EXPECT_DOUBLE_EQ(c.finger_velocities.velocity_mps[1].z, 0.004);

  c = round_trip(control::Command::open_fingers({0.005, 0.004}), got);
  ASSERT_EQ(c.kind, control::CommandKind::kOpen);
  EXPECT_DOUBLE_EQ(c.open.distance_m, 0.004);
  EXPECT_EQ(round_trip(control::Command::hold(), got).kind, control::CommandKind::kHold);
  EXPECT_EQ(round_trip(control::Command::stop(), got).kind, control::CommandKind::kStop);
  round_trip(control::Command::none(), got, DecodeStatus::kEmpty);
}

TEST(ArmCommand, RefusesValuesTheArmMustNotFollow) {
  ReceivedCommand got;
  control::MoveTo m;
  m.name = "MOVE1";
  m.max_speed_mps = 0.1;
  m.target.position_m.z = std::numeric_limits<double>::quiet_NaN();
  round_trip(control::Command::move(m), got, DecodeStatus::kInvalid);
  m.target.position_m.z = 0.2;
  m.max_speed_mps = -1;
  round_trip(control::Command::move(m), got, DecodeStatus::kInvalid);
  control::FingerVelocities v;
  v.velocity_mps[1].x = std::numeric_limits<double>::infinity();
  round_trip(control::Command::velocities(v), got, DecodeStatus::kInvalid);
  round_trip(control::Command::open_fingers({-0.005, 0.004}), got, DecodeStatus::kInvalid);

  v1::ArmCommand msg;
  auto* f = msg.mutable_finger_velocities()->add_fingers();
  f->set_sensor_id("thumb");  // not a configured fingertip
  EXPECT_EQ(read_arm_command(msg, kIds, got), DecodeStatus::kInvalid);
  f->set_sensor_id("left");
  msg.mutable_finger_velocities()->add_fingers()->set_sensor_id("left");  // twice
  EXPECT_EQ(read_arm_command(msg, kIds, got), DecodeStatus::kInvalid);

  // A long name is cut, not overflowed.
  v1::ArmCommand named;
  named.mutable_move_to()->set_name(std::string(100, 'M'));
  ASSERT_EQ(read_arm_command(named, kIds, got), DecodeStatus::kOk);
  EXPECT_EQ(std::string(got.command.move_to.name), std::string(kMaxNameLength, 'M'));
}

TEST(ArmState, SurvivesTheWire) {
  ArmStateData s;
  s.time_ns = 77;
  s.wrist = {{0.1, 0.2, 0.3}, 0.4};
  s.fingertip_position_m = {Vec3{-0.02, 0, 0}, Vec3{0.02, 0, 0}};
  s.fingertip_velocity_mps = {Vec3{0, 0, 0.001}, Vec3{0, 0, -0.001}};
  s.active_segment_id = 3;
  s.segment_done = true;
  s.holding = true;
  s.deadman = true;
  s.last_command_sequence = 12;
  v1::ArmState msg;
  fill_arm_state(s, kIds, msg);
  ArmStateData got;
  ASSERT_EQ(read_arm_state(msg, kIds, got), DecodeStatus::kOk);
  EXPECT_EQ(got.time_ns, 77);
  EXPECT_DOUBLE_EQ(got.wrist.yaw_rad, 0.4);
  EXPECT_DOUBLE_EQ(got.fingertip_position_m[1].x, 0.02);
  EXPECT_DOUBLE_EQ(got.fingertip_velocity_mps[0].z, 0.001);
  EXPECT_EQ(got.active_segment_id, 3U);
  EXPECT_TRUE(got.segment_done);
  EXPECT_TRUE(got.holding);
  EXPECT_TRUE(got.deadman);
  EXPECT_FALSE(got.limit);
  EXPECT_EQ(got.last_command_sequence, 12U);
  const control::ArmFeedback fb = to_feedback(got);
  EXPECT_EQ(fb.active_segment_id, 3U);
  EXPECT_TRUE(fb.segment_done);
  EXPECT_TRUE(fb.holding);
  EXPECT_TRUE(fb.deadman);
  msg.mutable_wrist()->set_yaw_rad(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(read_arm_state(msg, kIds, got), DecodeStatus::kInvalid);
}

TEST(Event, KindsMatchTheWireByName) {
  const std::pair<control::EventKind, v1::EventKind> pairs[] = {
      {control::EventKind::kPhase, v1::EVENT_KIND_PHASE},
      {control::EventKind::kTouch, v1::EVENT_KIND_TOUCH},
      {control::EventKind::kGraspingEnded, v1::EVENT_KIND_GRASPING_ENDED},
      {control::EventKind::kGraspClassified, v1::EVENT_KIND_GRASP_CLASSIFIED},
      {control::EventKind::kReleaseClassified, v1::EVENT_KIND_RELEASE_CLASSIFIED},
      {control::EventKind::kRecompress, v1::EVENT_KIND_RECOMPRESS},
      {control::EventKind::kOver, v1::EVENT_KIND_OVER},
      {control::EventKind::kTwistCycle, v1::EVENT_KIND_TWIST_CYCLE},
      {control::EventKind::kCapTight, v1::EVENT_KIND_CAP_TIGHT},
      {control::EventKind::kStaleHold, v1::EVENT_KIND_STALE_HOLD},
      {control::EventKind::kResumed, v1::EVENT_KIND_RESUMED},
      {control::EventKind::kDone, v1::EVENT_KIND_DONE},
      {control::EventKind::kAborted, v1::EVENT_KIND_ABORTED},
  };
  for (const auto& [core, wire] : pairs)
    EXPECT_EQ(to_proto(core), wire) << control::to_string(core);
}

TEST(Event, FillsEveryField) {
  control::Event e;
  e.kind = control::EventKind::kCapTight;
  e.phase = control::Phase::kTwistTurn;
  e.cycle = 3;
  e.fingertip = 1;
  e.has_element = true;
  e.element_id = 12;
  e.value = 9;
  e.text = "slips reached Ns";
  Answers a;
  a.add({1, 500, 42});
  v1::Event msg;
  fill_event(e, 99, a, kIds, msg);
  EXPECT_EQ(msg.time_ns(), 99);
  EXPECT_EQ(msg.kind(), v1::EVENT_KIND_CAP_TIGHT);
  EXPECT_EQ(msg.phase(), control::to_string(control::Phase::kTwistTurn));
  EXPECT_EQ(msg.cycle(), 3U);
  EXPECT_EQ(msg.sensor_id(), "right");
  EXPECT_EQ(msg.element_id(), 12U);
  EXPECT_DOUBLE_EQ(msg.value(), 9);
  EXPECT_EQ(msg.text(), "slips reached Ns");
  ASSERT_EQ(msg.answers_size(), 1);
  EXPECT_EQ(msg.answers(0).sequence(), 500U);
}

// --- Decision ------------------------------------------------------------------------------

TEST(Decision, FillsTheFreshFramesTheirReceiveTimesAndEachFingertipsFlags) {
  control::ControllerOutput out;
  out.phase = control::Phase::kLift;
  out.flags.fingertip[1].slip = true;
  out.flags.fingertip[1].touch = true;
  out.flags.fingertip[1].max_fz_n = 0.4;
  out.flags.fingertip[0].max_fz_n = std::nan("");
  // The first fill names four slipping elements of each fingertip, the second three of the right.
  out.flags.fingertip[0].slipping_elements = 4;
  out.flags.fingertip[0].slipping_ids = {1, 2, 3, 4};
  out.flags.fingertip[1].slipping_elements = 4;
  out.flags.fingertip[1].slipping_ids = {9, 8, 7, 6};
  out.slip_detector = control::SlipDetectorKind::kField;
  Answers on;
  on.add({1, 77, 1'000});
  const std::array<std::int64_t, control::kFingertips> received{5'000, 6'000};
  v1::Decision d;
  // Filled twice, the second over the first: storage reused, nothing left of the first.
  on.add({0, 76, 900});
  fill_decision(out, 9'000, on, received, 12, kIds, d);
  EXPECT_EQ(d.slip_detector(), "field");
  on.count = 1;
  out.flags.fingertip[0].slipping_elements = 0;
  out.flags.fingertip[1].slipping_elements = 3;
  out.flags.fingertip[1].slipping_ids = {40, 2, 17};
  out.slip_detector = control::SlipDetectorKind::kLearned;
  fill_decision(out, 9'500, on, received, 0, kIds, d);
  EXPECT_EQ(d.slip_detector(), "learned");
  EXPECT_EQ(d.time_ns(), 9'500);
  ASSERT_EQ(d.answers_size(), 1);
  EXPECT_EQ(d.answers(0).sensor_id(), "right");
  EXPECT_EQ(d.answers(0).sequence(), 77U);
  EXPECT_EQ(d.answers(0).camera_timestamp_ns(), 1'000);
  EXPECT_EQ(d.answers(0).receive_timestamp_ns(), 6'000);
  EXPECT_EQ(d.phase(), control::to_string(control::Phase::kLift));
  EXPECT_EQ(d.command_sequence(), 0U);
  ASSERT_EQ(d.fingertips_size(), 2);
  EXPECT_EQ(d.fingertips(0).sensor_id(), "left");
  EXPECT_FALSE(d.fingertips(0).slip());
  EXPECT_EQ(d.fingertips(0).max_fz_n(), 0.0);  // not finite: 0 on the wire
  EXPECT_TRUE(d.fingertips(1).slip());
  EXPECT_TRUE(d.fingertips(1).touch());
  EXPECT_FALSE(d.fingertips(1).over());
  EXPECT_EQ(d.fingertips(1).slipping_elements(), 3U);
  EXPECT_EQ(std::vector<std::uint32_t>(d.fingertips(1).slipping_element_ids().begin(),
                                       d.fingertips(1).slipping_element_ids().end()),
            (std::vector<std::uint32_t>{40, 2, 17}));
  EXPECT_EQ(d.fingertips(0).slipping_element_ids_size(), 0);
  EXPECT_DOUBLE_EQ(d.fingertips(1).max_fz_n(), 0.4);
}

// --- the topics -----------------------------------------------------------------------------

// Recorded logs, tools/python and users' subscriptions spell these names: they are fixed.
TEST(Topics, NamesOnTheWireAreFixed) {
  EXPECT_EQ(frame_topic("left"), "frame/left");
  EXPECT_EQ(stats_topic("left"), "stats/left");
  EXPECT_EQ(raw_topic("right"), "raw/right");
  EXPECT_STREQ(kEventTopic, "event");
  EXPECT_STREQ(kCommandTopic, "command");
  EXPECT_STREQ(kArmTopic, "arm");
  EXPECT_STREQ(kDecisionTopic, "decision");
  EXPECT_STREQ(kTruthTopic, "truth");
  // A prefix subscription to a kind receives each sensor's topic of that kind.
  EXPECT_TRUE(frame_topic("right").starts_with(kFrameTopicPrefix));
  EXPECT_TRUE(stats_topic("right").starts_with(kStatsTopicPrefix));
  EXPECT_TRUE(raw_topic("left").starts_with(kRawTopicPrefix));
}

TEST(Topics, BytesOfViewsTheStringItself) {
  const std::string s("a\0b", 3);
  const std::span<const std::uint8_t> b = bytes_of(s);
  EXPECT_EQ(static_cast<const void*>(b.data()), static_cast<const void*>(s.data()));
  ASSERT_EQ(b.size(), 3U);
  EXPECT_EQ(b[1], 0U);
  EXPECT_EQ(b[2], 'b');
}

// --- sockets: real ZeroMQ, loopback TCP and inproc -----------------------------------------

TEST(Sockets, PublishSubscribeOverTcp) {
  zmq::context_t ctx;
  Publisher pub(ctx, "tcp://127.0.0.1:*");
  const std::string endpoint = pub.endpoint();
  ASSERT_NE(endpoint.find("tcp://127.0.0.1:"), std::string::npos);
  Subscriber sub(ctx, {endpoint}, {kFrameTopicPrefix});
  TopicMessage msg;
  // A subscription takes a moment to reach the publisher: publish until one arrives (bounded).
  bool got = false;
  for (int i = 0; i < 200 && !got; ++i) {
    pub.send(kEventTopic, bytes_of("not subscribed"));
    pub.send(frame_topic("left"), bytes_of("hello"));
    got = sub.receive(msg, 10ms);
  }
  ASSERT_TRUE(got);
  EXPECT_EQ(msg.topic, frame_topic("left"));
  EXPECT_EQ(std::string(msg.payload.begin(), msg.payload.end()), "hello");
  // Only subscribed topics arrive.
  for (int i = 0; i < 20; ++i) {
    if (sub.receive(msg, 5ms)) {
      EXPECT_EQ(msg.topic, frame_topic("left"));
    }
  }
}

// run-system without root binds the nodes' publishers on ipc:// beside tcp:// (docs/system.md):
// one Publisher, comma-separated endpoints, every message on each of them.
TEST(Sockets, PublisherBindsEachOfSeveralEndpoints) {
  zmq::context_t ctx;
  char dir_template[] = "/tmp/wire_test_XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::string ipc = std::string("ipc://") + dir_template + "/pub.ipc";
  {
    Publisher pub(ctx, "tcp://127.0.0.1:*," + ipc);
    const std::string endpoints = pub.endpoint();
    const auto comma = endpoints.find(',');
    ASSERT_NE(comma, std::string::npos) << endpoints;
    const std::string tcp = endpoints.substr(0, comma);
    EXPECT_TRUE(tcp.starts_with("tcp://127.0.0.1:")) << endpoints;
    EXPECT_EQ(endpoints.substr(comma + 1), ipc);
    Subscriber over_tcp(ctx, {tcp}, {""});
    Subscriber over_ipc(ctx, {ipc}, {""});
    TopicMessage msg;
    bool tcp_got = false;
    bool ipc_got = false;
    for (int i = 0; i < 200 && !(tcp_got && ipc_got); ++i) {
      pub.send(kEventTopic, bytes_of("both"));
      tcp_got = tcp_got || over_tcp.receive(msg, 5ms);
      ipc_got = ipc_got || over_ipc.receive(msg, 5ms);
    }
    EXPECT_TRUE(tcp_got);
    EXPECT_TRUE(ipc_got);
    // An endpoint that cannot be bound throws naming it, not the list.
    try {
      Publisher bad(ctx, "tcp://127.0.0.1:*,nonsense://x");
      FAIL() << "bound nonsense";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("'nonsense://x'"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir_template);
}

// The rig wakes for its render instant on a timerfd beside its sockets: poll_readable reports
// the extra descriptor in the bit after the sockets' and does not report it when it is silent.
TEST(Sockets, PollReadableAlsoWakesOnAFileDescriptor) {
  zmq::context_t ctx;
  Subscriber sub(ctx, {"inproc://poll-fd"}, {""});
  std::array<zmq::socket_ref, 1> sockets{sub.socket()};
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  EXPECT_EQ(poll_readable(sockets, 20ms, pipe_fds[0]), 0U);
  ASSERT_EQ(::write(pipe_fds[1], "x", 1), 1);
  const auto before = std::chrono::steady_clock::now();
  EXPECT_EQ(poll_readable(sockets, 5000ms, pipe_fds[0]), 1U << 1);
  EXPECT_LT(std::chrono::steady_clock::now() - before, 2500ms) << "waited for the timeout";
  EXPECT_EQ(poll_readable(sockets, 20ms), 0U) << "without the descriptor nothing is readable";
  ::close(pipe_fds[0]);
  ::close(pipe_fds[1]);
}

// A subscriber that stops reading for a while (a recorder on a loaded machine) gets every message
// sent meanwhile as long as they fit the publisher's send queue; past it the publisher drops.
TEST(Sockets, PublisherKeepsItsSendQueueForASubscriberThatFallsBehind) {
  constexpr int kBurst = 2500;
  const std::vector<std::uint8_t> payload(64 * 1024, 7);
  const auto delivered = [&](int send_queue) {
    zmq::context_t ctx;
    Publisher pub(ctx, "tcp://127.0.0.1:*", nullptr, send_queue);
    zmq::socket_t sub(ctx, zmq::socket_type::sub);
    sub.set(zmq::sockopt::rcvhwm, 1);  // the subscriber's own queue holds (almost) nothing
    sub.set(zmq::sockopt::subscribe, "");
    sub.connect(pub.endpoint());
    zmq::message_t part;
    bool ready = false;  // the subscription has reached the publisher (bounded)
    for (int i = 0; i < 400 && !ready; ++i) {
      pub.send("ping", bytes_of("x"));
      ready = sub.recv(part, zmq::recv_flags::dontwait).has_value();
      if (!ready) std::this_thread::sleep_for(5ms);
    }
    EXPECT_TRUE(ready);
    while (sub.recv(part, zmq::recv_flags::dontwait)) {
    }
    for (int i = 0; i < kBurst; ++i)
      pub.send("big", payload);  // nobody reads meanwhile
    int n = 0;
    sub.set(zmq::sockopt::rcvtimeo, 200);
    bool first = true;  // the next part is a topic
    while (sub.recv(part)) {
      if (first && part.to_string_view() == "big") ++n;
      first = !part.more();
    }
    return n;
  };
  EXPECT_EQ(delivered(5000), kBurst);
  EXPECT_LT(delivered(kDefaultSendQueue), kBurst * 3 / 4);
}

TEST(Sockets, SubscriberCountsMessagesOfTheWrongShape) {
  zmq::context_t ctx;
  zmq::socket_t raw(ctx, zmq::socket_type::pub);
  raw.bind("inproc://shape");
  Subscriber sub(ctx, {"inproc://shape"}, {""});
  TopicMessage msg;
  // Wait for the subscription to reach the publisher: ping until a ping arrives (bounded).
  bool ready = false;
  for (int i = 0; i < 200 && !ready; ++i) {
    raw.send(zmq::str_buffer("ping"), zmq::send_flags::sndmore);
    raw.send(zmq::str_buffer("x"), zmq::send_flags::none);
    ready = sub.receive(msg, 5ms);
  }
  ASSERT_TRUE(ready);
  while (sub.receive(msg, 5ms)) {
  }
  raw.send(zmq::str_buffer("single part"), zmq::send_flags::none);
  raw.send(zmq::str_buffer("a"), zmq::send_flags::sndmore);
  raw.send(zmq::str_buffer("b"), zmq::send_flags::sndmore);
  raw.send(zmq::str_buffer("c"), zmq::send_flags::none);
  raw.send(zmq::str_buffer("frame/x"), zmq::send_flags::sndmore);
  raw.send(zmq::str_buffer("good"), zmq::send_flags::none);
  bool good = false;
  for (int i = 0; i < 10 && !good; ++i) {
    if (sub.receive(msg, 50ms)) good = msg.topic == "frame/x";
  }
  EXPECT_TRUE(good);
  EXPECT_EQ(sub.malformed(), 2U);
}

TEST(Sockets, DealerRouterRoundTrip) {
  zmq::context_t ctx;
  Router router(ctx, "tcp://127.0.0.1:*");
  Dealer dealer(ctx, router.endpoint());
  ASSERT_TRUE(dealer.send(bytes_of("command")));
  std::string peer;
  std::vector<std::uint8_t> payload;
  ASSERT_TRUE(router.receive(peer, payload, 2000ms));
  EXPECT_EQ(std::string(payload.begin(), payload.end()), "command");
  ASSERT_TRUE(router.send(peer, bytes_of("state")));
  ASSERT_TRUE(dealer.receive(payload, 2000ms));
  EXPECT_EQ(std::string(payload.begin(), payload.end()), "state");
  EXPECT_FALSE(router.send("nobody", bytes_of("x")));
  EXPECT_FALSE(dealer.receive(payload, 1ms));
}

TEST(Sockets, OversizedMessagesNeverArrive) {
  zmq::context_t ctx;
  Router router(ctx, "tcp://127.0.0.1:*");
  {
    Dealer big(ctx, router.endpoint());
    ASSERT_TRUE(big.send(std::vector<std::uint8_t>(kMaxMessageBytes + 1, 7)));
    std::string peer;
    std::vector<std::uint8_t> payload;
    EXPECT_FALSE(router.receive(peer, payload, 300ms));
  }
  Dealer small(ctx, router.endpoint());
  ASSERT_TRUE(small.send(bytes_of("fine")));
  std::string peer;
  std::vector<std::uint8_t> payload;
  EXPECT_TRUE(router.receive(peer, payload, 2000ms));
}

TEST(Sockets, BadEndpointsThrowNamingThem) {
  zmq::context_t ctx;
  Publisher first(ctx, "tcp://127.0.0.1:*");
  try {
    Publisher second(ctx, first.endpoint());
    FAIL() << "bound twice";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(first.endpoint()), std::string::npos) << e.what();
  }
  EXPECT_THROW(Subscriber(ctx, {"nonsense://x"}, {""}), std::runtime_error);
}

}  // namespace
}  // namespace tactile::wire
