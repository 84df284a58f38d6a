#include "fault_support.hpp"

#include <fmt/core.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <regex>
#include <set>
#include <stdexcept>

#include "process.hpp"
#include "sensor_config.hpp"
#include "support/child_process.hpp"
#include "synthetic.hpp"
#include "tactile/camera/aravis_camera.hpp"
#include "tactile/camera/camera.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/pgm.hpp"
#include "tactile/util/random.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::faults {
namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;

testing::SceneOptions scene() {
  testing::SceneOptions o;
  o.width = kWidth;
  o.height = kHeight;
  o.bit_depth = 8;
  o.noise_sigma = 2.0;
  return o;
}

// Elements that blink: a spot in some frames only, so contact comes and goes.
bool blinking(std::size_t element) {
  return element % 7 == 3;
}

}  // namespace

Calibration fault_calibration(const std::string& sensor_id) {
  Calibration cal = testing::grid_calibration(scene(), 10, 8, 60, 14);
  cal.sensor_id = sensor_id;
  return cal;
}

KnownImages::KnownImages(const Calibration& cal, int count) {
  if (count < 8) throw std::invalid_argument("KnownImages: at least 8 frames");
  const testing::SceneOptions o = scene();
  {
    testing::SceneOptions quiet = o;
    quiet.noise_sigma = 0;
    util::Random rng(1);
    testing::render(quiet, {}, rng, background_);
  }
  const testing::SceneRenderer renderer(o, &cal);
  images_.resize(static_cast<std::size_t>(count));
  std::vector<testing::Spot> spots;
  for (int j = 0; j < count; ++j) {
    const double phase = 2 * std::numbers::pi * j / count;
    spots.clear();
    for (std::size_t e = 0; e < cal.elements.size(); ++e) {
      const double ed = static_cast<double>(e);
      if (blinking(e) && std::sin(phase + ed) < 0.2) continue;
      testing::Spot s;
      s.center = {cal.elements[e].center_px.x + 1.5 * std::sin(phase + 0.7 * ed),
                  cal.elements[e].center_px.y + 1.2 * std::cos(2 * phase + 0.3 * ed)};
      s.peak = 60 + 50 * (0.5 + 0.5 * std::sin(3 * phase + ed));
      s.sigma = 2.2;
      spots.push_back(s);
    }
    util::Random rng(1000 + static_cast<std::uint64_t>(j));
    renderer.render(spots, rng, images_[static_cast<std::size_t>(j)]);
  }
}

KnownCamera::KnownCamera(const KnownImages& images, const std::string& address,
                         const std::string& serial, double gvsp_lost_ratio)
    : images_(images) {
  camera::FakeGvCameraOptions o;
  o.address = address;
  o.serial = serial;
  o.width = kWidth;
  o.height = kHeight;
  o.pixel_format = PixelFormat::kMono8;
  o.frame_rate_hz = 100;
  o.gvsp_lost_ratio = gvsp_lost_ratio;
  fake_ = std::make_unique<camera::FakeGvCamera>(o);
  if (!fake_->publish(images_.image(0).view(), 0, images_.code().encode(0))) {
    throw std::runtime_error("KnownCamera: the fake camera refused image 0");
  }
  // Runs on the camera's thread after each frame's copy: the next frame gets the next image.
  fake_->set_sent_observer([this](const camera::SentFrame& sent) {
    const std::uint64_t k = sent.frame_id + 1;
    (void)fake_->publish(images_.image(k).view(), k, images_.code().encode(k));
  });
}

std::filesystem::path write_sensor_config(const std::filesystem::path& dir,
                                          const std::vector<CameraEntry>& cameras,
                                          const Image& reference, const std::string& publish,
                                          const std::string& name) {
  const std::filesystem::path file = dir / name;
  std::ofstream out(file);
  out << "format: tactile-sensor/1\n"
      << "publish: " << publish << "\n"
      << "stats_period_s: 0.2\n"
      << "cameras:\n";
  for (const CameraEntry& c : cameras) {
    config::save_calibration(dir / (c.sensor_id + ".yaml"), fault_calibration(c.sensor_id));
    util::write_pgm(dir / (c.sensor_id + "-reference.pgm"), reference.view());
    out << "  - sensor_id: " << c.sensor_id << "\n"
        << "    camera: " << c.address << "\n"
        << "    calibration: " << c.sensor_id << ".yaml\n"
        << "    reference: " << c.sensor_id << "-reference.pgm\n"
        << "    fps: 100\n";
    for (const auto& key : c.extra_keys)
      out << "    " << key << "\n";
  }
  out.close();
  if (!out) throw std::runtime_error("cannot write " + file.string());
  return file;
}

Collector::Collector(zmq::context_t& ctx, const std::vector<std::string>& endpoints)
    : sub_(ctx, endpoints, {wire::kFrameTopicPrefix, wire::kStatsTopicPrefix}) {}

void Collector::poll(std::chrono::milliseconds wait) {
  auto timeout = wait;
  while (sub_.receive(msg_, timeout)) {
    timeout = std::chrono::milliseconds(0);
    if (wire::decode(msg_.payload, env_) != wire::DecodeStatus::kOk) {
      ++undecodable_;
      continue;
    }
    if (env_.has_tactile_frame()) {
      frames_[env_.tactile_frame().sensor_id()].push_back(env_.tactile_frame());
    } else if (env_.has_sensor_stats()) {
      const std::string& id = env_.sensor_stats().sensor_id();
      stats_[id].push_back({env_.sensor_stats(), frames(id).size()});
    } else {
      ++undecodable_;
    }
  }
}

const std::vector<v1::TactileFrame>& Collector::frames(const std::string& sensor) const {
  static const std::vector<v1::TactileFrame> none;
  const auto it = frames_.find(sensor);
  return it == frames_.end() ? none : it->second;
}

const std::vector<Collector::SeenStats>& Collector::stats(const std::string& sensor) const {
  static const std::vector<SeenStats> none;
  const auto it = stats_.find(sensor);
  return it == stats_.end() ? none : it->second;
}

std::size_t Collector::complete(const std::string& sensor) const {
  std::size_t n = 0;
  for (const auto& f : frames(sensor))
    n += f.status() == v1::FRAME_STATUS_COMPLETE ? 1 : 0;
  return n;
}

namespace {

// The first field in which two element readings differ, or empty.
std::string difference(const v1::ElementReading& got, const v1::ElementReading& want,
                       bool with_displacement) {
  const auto field = [](const char* name, auto g, auto w) -> std::string {
    if (g == w) return {};
    return fmt::format("{} is {}, the true image gives {}", name, g, w);
  };
  std::string d;
  const auto check = [&](std::string s) {
    if (d.empty()) d = std::move(s);
  };
  check(field("id", got.id(), want.id()));
  check(field("contact", got.contact(), want.contact()));
  check(field("g", got.g(), want.g()));
  check(field("x_mm", got.x_mm(), want.x_mm()));
  check(field("y_mm", got.y_mm(), want.y_mm()));
  check(field("ux_mm", got.ux_mm(), want.ux_mm()));
  check(field("uy_mm", got.uy_mm(), want.uy_mm()));
  check(field("fx_n", got.fx_n(), want.fx_n()));
  check(field("fy_n", got.fy_n(), want.fy_n()));
  check(field("fz_n", got.fz_n(), want.fz_n()));
  if (with_displacement) {
    check(field("has_displacement", got.has_displacement(), want.has_displacement()));
    check(field("dx_mm", got.dx_mm(), want.dx_mm()));
    check(field("dy_mm", got.dy_mm(), want.dy_mm()));
  }
  return d;
}

}  // namespace

TruthSource known_images_truth(const KnownImages& images) {
  return [&images](const v1::TactileFrame& f, std::string& why) -> const Image* {
    const auto k = images.code().decode(f.camera_timestamp_ns());
    if (!k) {
      why = fmt::format("camera timestamp {} is no frame the camera was given",
                        f.camera_timestamp_ns());
      return nullptr;
    }
    return &images.image(*k);
  };
}

TruthSource aravis_ramp_truth(const Calibration& cal) {
  // sensor_node sets the camera's region of interest (roi: auto; the fake's increments are 1),
  // and arv-fake-gv-camera draws its ramp in the frame's own coordinates: a sensor pixel (x, y)
  // of the region holds the ramp at (x - region.x, y - region.y). Outside it nothing is sent
  // and nothing is measured.
  const Region region = region_of_interest(cal);
  auto image = std::make_shared<Image>(cal.width, cal.height, PixelFormat::kMono8);
  return [image, region](const v1::TactileFrame& f, std::string& why) -> const Image* {
    if (f.camera_frame_id() == 0 || f.camera_frame_id() > 65535) {
      why = fmt::format("block id {} is not a GigE Vision 1.x id", f.camera_frame_id());
      return nullptr;
    }
    for (int y = region.y; y < region.y + region.height; ++y) {
      for (int x = region.x; x < region.x + region.width; ++x) {
        const auto sum =
            static_cast<std::uint64_t>(x - region.x + y - region.y) + f.camera_frame_id();
        image->set(x, y, static_cast<std::uint32_t>(sum % 255));
      }
    }
    return image.get();
  };
}

TruthReport check_against_truth(const std::vector<v1::TactileFrame>& frames,
                                const TruthSource& truth, const Image& reference,
                                const Calibration& cal, const ExtractorOptions& options) {
  TruthReport r;
  const auto fail = [&r](std::string what) {
    if (r.failures.size() < 10) r.failures.push_back(std::move(what));
  };
  Extractor extractor(cal, options);
  extractor.begin_reference();
  const ReferenceResult ref = extractor.add_reference_frame(reference.view());
  const ReferenceResult done =
      ref.status == ReferenceStatus::kCollecting ? extractor.finish_reference() : ref;
  if (done.status != ReferenceStatus::kComplete) {
    fail(std::string("the reference is refused: ") + to_string(done.status));
    return r;
  }
  camera::FrameSequencer sequencer;
  std::set<std::uint64_t> sequences_seen;
  v1::TactileFrame expected;
  bool have_measured = false;
  bool first_complete_seen = false;
  std::uint64_t last_measured = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const v1::TactileFrame& f = frames[i];
    ++r.frames;
    const std::string where =
        fmt::format("frame sequence {} (camera block {}, status {})", f.sequence(),
                    f.camera_frame_id(), v1::FrameStatus_Name(f.status()));
    if (i == 0) {
      r.first_seen_was_first_published = f.sequence() == 0;
    } else if (f.sequence() != frames[i - 1].sequence() + 1) {
      fail(where + ": sensor_node's sequence does not follow " +
           std::to_string(frames[i - 1].sequence()));
    }
    if (f.camera_frame_id() == 0) {
      // Its leader was lost: the id is unknown, it has no place in the stream and counts among
      // the frames the next identified one skipped.
      ++r.stale_id;
      if (f.status() == v1::FRAME_STATUS_COMPLETE) fail(where + ": COMPLETE without a block id");
      if (f.frames_skipped() != 0) fail(where + ": frames_skipped on a frame without a block id");
      ++r.statuses[f.status()];
      ++r.incomplete;
      if (f.elements_size() != 0)
        fail(fmt::format("{}: carries {} element readings", where, f.elements_size()));
      continue;
    }
    const camera::FrameSequencer::Step step = sequencer.next(f.camera_frame_id());
    sequences_seen.insert(step.sequence);
    if (step.late) {
      ++r.stale_id;
      // What the camera seam cannot place in the stream must never be measured.
      if (f.status() == v1::FRAME_STATUS_COMPLETE) fail(where + ": COMPLETE with an old block id");
    }
    const std::uint64_t skipped = step.late || step.first_after_start ? 0 : step.frames_lost;
    // The first identified frame the test saw has nothing to count from (the test may have
    // joined late, or seen only frames without a block id before it).
    if (!step.first_after_start && f.frames_skipped() != skipped) {
      // The frames before it, to tell which arrival order the two sides disagree on.
      std::string before;
      for (std::size_t j = i >= 4 ? i - 4 : 0; j < i; ++j) {
        before += fmt::format(" [seq {} block {} {} skipped {}]", frames[j].sequence(),
                              frames[j].camera_frame_id(), v1::FrameStatus_Name(frames[j].status()),
                              frames[j].frames_skipped());
      }
      fail(fmt::format("{}: frames_skipped {}, the block ids say {}; before it:{}", where,
                       f.frames_skipped(), skipped, before));
    }
    r.frames_lost += f.frames_skipped();
    ++r.statuses[f.status()];
    if (f.status() != v1::FRAME_STATUS_COMPLETE) {
      ++r.incomplete;
      if (f.elements_size() != 0) {
        fail(fmt::format("{}: carries {} element readings", where, f.elements_size()));
      }
      if (f.status() == v1::FRAME_STATUS_NO_REFERENCE ||
          f.status() == v1::FRAME_STATUS_WRONG_FORMAT ||
          f.status() == v1::FRAME_STATUS_UNSPECIFIED) {
        fail(where + ": unexpected status for a frame of the right format with a reference");
      }
      continue;
    }
    ++r.complete;
    std::string why;
    const Image* image = truth(f, why);
    if (image == nullptr) {
      fail(where + ": " + why);
      continue;
    }
    const bool after_gap = have_measured && step.sequence != last_measured + 1;
    const bool after_complete = have_measured && step.sequence == last_measured + 1;
    if (extractor.measure(image->view(), {step.sequence, f.camera_timestamp_ns()}) !=
        MeasureStatus::kOk) {
      fail(where + ": the true image cannot be measured");
      continue;
    }
    have_measured = true;
    last_measured = step.sequence;
    wire::FrameHeader h;
    h.status = v1::FRAME_STATUS_COMPLETE;
    wire::fill_tactile_frame(cal.sensor_id, h, extractor.readings(), cal.mm_per_px, expected);
    // sensor_node may have measured a frame before this collector subscribed: only the first
    // whole frame seen can then have a predecessor this replay does not know.
    const bool compare_displacement = first_complete_seen || r.first_seen_was_first_published;
    first_complete_seen = true;
    if (f.elements_size() != expected.elements_size()) {
      fail(fmt::format("{}: {} element readings, the calibration has {}", where, f.elements_size(),
                       expected.elements_size()));
      continue;
    }
    std::size_t displaced = 0;
    for (int e = 0; e < f.elements_size(); ++e) {
      const v1::ElementReading& got = f.elements(e);
      ++r.readings_checked;
      if (got.has_displacement()) ++displaced;
      const std::string d = difference(got, expected.elements(e), compare_displacement);
      if (!d.empty()) {
        fail(fmt::format("{}: element {}: {}", where, got.id(), d));
        break;
      }
    }
    r.displacements_measured += displaced;
    if (after_gap) {
      ++r.complete_after_gap;
      r.displacements_after_gap += displaced;
      if (displaced > 0) {
        fail(fmt::format("{}: {} elements carry a displacement across a gap", where, displaced));
      }
    }
    if (after_complete) ++r.complete_after_complete;
  }
  if (!sequences_seen.empty()) {
    const std::uint64_t span = *sequences_seen.rbegin() - *sequences_seen.begin() + 1;
    r.never_received = static_cast<std::size_t>(span - sequences_seen.size());
  }
  return r;
}

std::string describe(const TruthReport& r) {
  std::string statuses;
  for (const auto& [s, n] : r.statuses) {
    statuses += fmt::format(" {}={}", v1::FrameStatus_Name(static_cast<v1::FrameStatus>(s)), n);
  }
  std::string s = fmt::format(
      "{} frames: {} complete, {} incomplete ({} ), {} with an old block id; {} skipped on the "
      "wire, {} block ids not seen; complete after a gap {}, after a complete frame {}; "
      "displacements {} ({} after a gap); {} readings checked",
      r.frames, r.complete, r.incomplete, statuses, r.stale_id, r.frames_lost, r.never_received,
      r.complete_after_gap, r.complete_after_complete, r.displacements_measured,
      r.displacements_after_gap, r.readings_checked);
  for (const auto& f : r.failures)
    s += "\n  " + f;
  return s;
}

LossRun run_sensor_node_under_loss(const std::string& sensor_node, const LossSetup& setup) {
  using namespace std::chrono_literals;
  LossRun run;
  testing::TempDir dir;
  const Calibration cal = fault_calibration("left");
  const KnownImages images(cal, 50);
  Image black(cal.width, cal.height, PixelFormat::kMono8);
  const bool arv = setup.arv_per_thousand >= 0;
  const Image& reference = arv ? black : images.background();
  const std::string endpoint = "ipc://" + (dir / "frames").string();
  const auto config =
      write_sensor_config(dir.path(), {{"left", "127.0.0.2", {}}}, reference, endpoint);
  const sensor::SensorConfig parsed = sensor::load_sensor_config(config, nullptr);

  std::unique_ptr<KnownCamera> known;
  std::unique_ptr<camera::testing::ChildProcess> arv_camera;
  if (arv) {
    arv_camera = std::make_unique<camera::testing::ChildProcess>(
        std::vector<std::string>{"arv-fake-gv-camera-0.8", "-i", "127.0.0.2", "-s", "LOSSPROC",
                                 "-r", std::to_string(setup.arv_per_thousand)});
    const std::int64_t deadline = util::monotonic_ns() + 10'000'000'000LL;
    while (!camera::gvcp_device_answers("127.0.0.2", 300ms)) {
      if (!arv_camera->running() || util::monotonic_ns() > deadline) {
        run.problem =
            "arv-fake-gv-camera-0.8 does not answer on 127.0.0.2: " + arv_camera->output();
        return run;
      }
    }
  } else {
    known = std::make_unique<KnownCamera>(images, "127.0.0.2", "LOSS", setup.gvsp_lost_ratio);
  }
  std::unique_ptr<NftLoss> nft;
  if (setup.nft_percent > 0) nft = std::make_unique<NftLoss>("127.0.0.2", setup.nft_percent);

  zmq::context_t ctx;
  Collector collector(ctx, {endpoint});
  const std::int64_t start = util::monotonic_ns();
  camera::testing::ChildProcess node({sensor_node, "--config", config.string()});
  const std::int64_t deadline = start + std::chrono::nanoseconds(setup.limit).count();
  while (collector.frames("left").size() < setup.frames) {
    collector.poll(50ms);
    (void)node.output();  // keep its pipe from filling
    if (!node.running()) {
      run.problem = "sensor_node ended early";
      break;
    }
    if (util::monotonic_ns() > deadline) {
      run.problem = fmt::format("only {} frames within {} s", collector.frames("left").size(),
                                setup.limit.count());
      break;
    }
  }
  run.exit_status = node.stop(10s);
  run.seconds = static_cast<double>(util::monotonic_ns() - start) * 1e-9;
  // What was in flight when it stopped (its PUB socket does not linger).
  collector.poll(200ms);
  run.log = node.output();
  if (known) run.frames_sent = known->fake().frames_sent();
  if (nft) run.nft = nft->counts();
  run.exit_lines = sensor_node_exit_lines(run.log);
  run.stats = collector.stats("left");
  const TruthSource truth = arv ? aravis_ramp_truth(cal) : known_images_truth(images);
  run.truth = check_against_truth(collector.frames("left"), truth, reference,
                                  parsed.cameras.front().calibration, parsed.measurement);
  return run;
}

std::string describe(const LossRun& run) {
  std::string s = describe(run.truth);
  s += fmt::format("\nsensor_node exit status {} after {:.1f} s", run.exit_status, run.seconds);
  if (!run.problem.empty()) s += "; problem: " + run.problem;
  if (run.nft.sent > 0) {
    s += fmt::format("; nft dropped {} of {} camera packets", run.nft.dropped, run.nft.sent);
  }
  s += "\nsensor_node log:\n" + run.log;
  return s;
}

namespace {

constexpr const char* kTable = "tactile_faults";

std::string nft(std::vector<std::string> args) {
  args.insert(args.begin(), "nft");
  const auto r = camera::testing::run_program(args, std::chrono::seconds(10));
  if (r.timed_out || r.status != 0) {
    std::string cmd;
    for (const auto& a : args)
      cmd += a + " ";
    throw std::runtime_error(
        "the packet-loss test needs nft (package nftables) and CAP_NET_ADMIN "
        "in its network namespace; `" +
        cmd + "` failed (status " + std::to_string(r.status) + "): " + r.output);
  }
  return r.output;
}

}  // namespace

NftLoss::NftLoss(const std::string& camera_address, int percent) {
  if (percent < 1 || percent > 100) throw std::invalid_argument("NftLoss: percent in 1..100");
  nft({"add", "table", "inet", kTable});
  active_ = true;
  nft({"add", "chain", "inet", kTable, "input", "{", "type", "filter", "hook", "input", "priority",
       "0", ";", "policy", "accept", ";", "}"});
  // What the camera sends goes anywhere but to its own GVCP port (the receiver's requests do).
  const std::vector<std::string> from_camera{"ip",    "saddr", camera_address, "udp",
                                             "dport", "!=",    "3956"};
  std::vector<std::string> count{"add", "rule", "inet", kTable, "input"};
  count.insert(count.end(), from_camera.begin(), from_camera.end());
  count.push_back("counter");
  nft(count);
  std::vector<std::string> drop{"add", "rule", "inet", kTable, "input"};
  drop.insert(drop.end(), from_camera.begin(), from_camera.end());
  for (const char* w : {"numgen", "random", "mod", "100", "<"})
    drop.emplace_back(w);
  drop.push_back(std::to_string(percent));
  drop.emplace_back("counter");
  drop.emplace_back("drop");
  nft(drop);
}

NftLoss::~NftLoss() {
  if (!active_) return;
  try {
    nft({"delete", "table", "inet", kTable});
  } catch (const std::exception&) {  // the namespace goes with the test process anyway
  }
}

NftLoss::Counts NftLoss::counts() const {
  const std::string listing = nft({"list", "table", "inet", kTable});
  static const std::regex counter(R"(counter packets (\d+))");
  std::vector<std::uint64_t> values;
  for (auto it = std::sregex_iterator(listing.begin(), listing.end(), counter);
       it != std::sregex_iterator(); ++it) {
    values.push_back(std::stoull((*it)[1].str()));
  }
  if (values.size() != 2) throw std::runtime_error("unexpected nft listing: " + listing);
  return {values[0], values[1]};
}

std::vector<PublishedLine> sensor_node_exit_lines(const std::string& log) {
  static const std::regex line(
      R"(published (\d+) frames \((\d+) measured, (\d+) not measured\), camera restarts (\d+))");
  std::vector<PublishedLine> out;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), line); it != std::sregex_iterator();
       ++it) {
    out.push_back({std::stoull((*it)[1].str()), std::stoull((*it)[2].str()),
                   std::stoull((*it)[3].str()), std::stoull((*it)[4].str())});
  }
  return out;
}

std::optional<HandExitLine> hand_node_exit_line(const std::string& log) {
  static const std::regex line(
      R"(frames used (\d+)/(\d+), skipped incomplete (\d+)/(\d+), undecodable (\d+))");
  std::smatch m;
  if (!std::regex_search(log, m, line)) return std::nullopt;
  HandExitLine h;
  h.used[0] = std::stoull(m[1].str());
  h.used[1] = std::stoull(m[2].str());
  h.skipped_incomplete[0] = std::stoull(m[3].str());
  h.skipped_incomplete[1] = std::stoull(m[4].str());
  h.undecodable = std::stoull(m[5].str());
  return h;
}

std::size_t count_lines(const std::string& log, const std::string& part) {
  std::size_t n = 0;
  std::size_t begin = 0;
  while (begin < log.size()) {
    std::size_t end = log.find('\n', begin);
    if (end == std::string::npos) end = log.size();
    if (std::string_view(log).substr(begin, end - begin).find(part) != std::string_view::npos) ++n;
    begin = end + 1;
  }
  return n;
}

}  // namespace tactile::faults
