#pragma once

// What the fault-injection tests share: frames whose truth is known, a fake GigE Vision camera
// that sends them, sensor_node's files, a collector of what sensor_node publishes, the check of
// every published frame against the truth, nft packet loss, and readers of the programs' logs.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "support/test_images.hpp"
#include "tactile/calibration.hpp"
#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/extractor.hpp"
#include "tactile/image.hpp"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/sockets.hpp"

namespace tactile::faults {

// 640 x 480 Mono8, 10 x 8 elements 60 px apart: the disks span rows 15 to 464, so each GVSP
// packet of 65000 bytes (about 101 rows) carries pixels of some element, and a frame that lost
// any data packet has elements whose pixels are stale.
Calibration fault_calibration(const std::string& sensor_id);

// `count` frames with one moving, brightening and dimming spot on every element (frame k is
// image k % count), so every frame differs from the ones a few frames before it (the receiver's
// buffers hold those), and some elements leave and regain contact. The camera timestamp of
// frame k is code.encode(k).
class KnownImages {
 public:
  KnownImages(const Calibration& cal, int count);
  const Image& image(std::uint64_t k) const { return images_[k % images_.size()]; }
  // The no-load frame: background only (sensor_node's --reference).
  const Image& background() const { return background_; }
  const camera::testing::TimestampCode& code() const { return code_; }

 private:
  std::vector<Image> images_;
  Image background_;
  camera::testing::TimestampCode code_;
};

// An in-process fake GigE Vision camera (the rig's FakeGvCamera) whose k-th frame is image k:
// after each frame it publishes the next image.
class KnownCamera {
 public:
  KnownCamera(const KnownImages& images, const std::string& address, const std::string& serial,
              double gvsp_lost_ratio);
  camera::FakeGvCamera& fake() { return *fake_; }

 private:
  const KnownImages& images_;
  std::unique_ptr<camera::FakeGvCamera> fake_;
};

// sensor_node's files in `dir`: per camera its calibration (<id>.yaml), its no-load reference
// (<id>-reference.pgm) and an entry in the configuration file `name`, which is returned.
struct CameraEntry {
  std::string sensor_id;
  std::string address;
  std::vector<std::string> extra_keys;  // more keys of the camera's entry ("retry_max_s: 1.6")
};
std::filesystem::path write_sensor_config(const std::filesystem::path& dir,
                                          const std::vector<CameraEntry>& cameras,
                                          const Image& reference, const std::string& publish,
                                          const std::string& name = "sensor.yaml");

// Everything sensor_node publishes, per sensor, in arrival order.
class Collector {
 public:
  Collector(zmq::context_t& ctx, const std::vector<std::string>& endpoints);
  // Receives whatever arrives within `wait` (at least one wait, then what is queued).
  void poll(std::chrono::milliseconds wait);
  const std::vector<v1::TactileFrame>& frames(const std::string& sensor) const;
  // SensorStats with the number of that sensor's frames received before it.
  struct SeenStats {
    v1::SensorStats stats;
    std::size_t frames_before = 0;
  };
  const std::vector<SeenStats>& stats(const std::string& sensor) const;
  std::size_t complete(const std::string& sensor) const;
  std::uint64_t undecodable() const { return undecodable_; }

 private:
  wire::Subscriber sub_;
  wire::TopicMessage msg_;
  v1::Envelope env_;
  std::map<std::string, std::vector<v1::TactileFrame>> frames_;
  std::map<std::string, std::vector<SeenStats>> stats_;
  std::uint64_t undecodable_ = 0;
};

// The image a camera sent as the frame a TactileFrame reports, or nullptr (and why).
using TruthSource = std::function<const Image*(const v1::TactileFrame&, std::string& why)>;
// KnownImages, by camera timestamp.
TruthSource known_images_truth(const KnownImages& images);
// arv-fake-gv-camera-0.8's own Mono8 image: a diagonal ramp (x + y + block id) mod 255 in the
// frame's coordinates, the frame being the region of interest sensor_node sets for `cal`.
TruthSource aravis_ramp_truth(const Calibration& cal);

// The published frames of one sensor checked against the truth: the frames the camera sent,
// measured again here by the measurement core with sensor_node's options and reference, in the
// order sensor_node measured them.
struct TruthReport {
  std::size_t frames = 0;
  std::size_t complete = 0;
  std::size_t incomplete = 0;           // any status but COMPLETE
  std::map<int, std::size_t> statuses;  // FrameStatus -> count
  std::uint64_t frames_lost = 0;        // sum of frames_skipped
  // Frames whose block id is not newer than the newest seen. In every run so far each was an
  // incomplete frame whose leader packet was lost: Aravis 0.8 sets a buffer's frame id and
  // timestamp from the leader only, so such a frame carries those of the buffer's previous use
  // (buffer_count frames earlier), and its true id shows as a gap (docs/reliability.md).
  std::size_t stale_id = 0;
  std::size_t never_received = 0;  // block ids in the range seen that no frame on the wire carries
  std::size_t complete_after_gap = 0;           // COMPLETE after a lost or incomplete frame
  std::size_t complete_after_complete = 0;      // COMPLETE right after a COMPLETE frame
  std::size_t displacements_measured = 0;       // element readings with has_displacement
  std::size_t displacements_after_gap = 0;      // ... in a COMPLETE frame after a gap (must be 0)
  std::size_t readings_checked = 0;             // element readings compared with the truth
  std::vector<std::string> failures;            // the first few differences, described
  bool first_seen_was_first_published = false;  // the collector saw sensor_node's sequence 0
};
TruthReport check_against_truth(const std::vector<v1::TactileFrame>& frames,
                                const TruthSource& truth, const Image& reference,
                                const Calibration& cal, const ExtractorOptions& options);
std::string describe(const TruthReport& r);

// Drops `percent` % of the UDP packets the camera at `camera_address` sends (GVSP stream and
// GVCP answers; not the packets sent to it), with nft in the current network namespace, and
// counts them. The table goes with the object.
class NftLoss {
 public:
  NftLoss(const std::string& camera_address, int percent);
  ~NftLoss();
  NftLoss(const NftLoss&) = delete;
  NftLoss& operator=(const NftLoss&) = delete;
  struct Counts {
    std::uint64_t sent = 0;     // packets of the camera that reached the rule
    std::uint64_t dropped = 0;  // of which dropped
  };
  Counts counts() const;

 private:
  bool active_ = false;
};

// Numbers of sensor_node's exit lines "published P frames (M measured, K not measured), camera
// restarts R", one per camera in configuration order.
struct PublishedLine {
  std::uint64_t published = 0;
  std::uint64_t measured = 0;
  std::uint64_t not_measured = 0;
  std::uint64_t camera_restarts = 0;
};
std::vector<PublishedLine> sensor_node_exit_lines(const std::string& log);

// One run of sensor_node (a child process) against one camera on 127.0.0.2 with packet loss:
// collects `frames` TactileFrames of sensor "left", stops sensor_node with SIGTERM and checks
// every frame against the truth.
struct LossSetup {
  double gvsp_lost_ratio = 0;  // the in-process camera drops each GVSP packet so often
  int arv_per_thousand = -1;   // >= 0: arv-fake-gv-camera-0.8 -r N instead (its ramp is the truth)
  int nft_percent = 0;         // > 0: nft drops this % of the camera's packets
  std::size_t frames = 300;    // TactileFrames to collect
  std::chrono::seconds limit{40};
};
struct LossRun {
  TruthReport truth;
  std::vector<PublishedLine> exit_lines;
  int exit_status = -1;
  std::string log;  // sensor_node's standard output and error
  std::vector<Collector::SeenStats> stats;
  NftLoss::Counts nft;
  std::uint64_t frames_sent = 0;  // by the in-process camera
  double seconds = 0;             // from sensor_node's start to its exit
  std::string problem;            // why the run did not collect its frames, if it did not
};
LossRun run_sensor_node_under_loss(const std::string& sensor_node, const LossSetup& setup);
std::string describe(const LossRun& run);

// hand_node's exit line: "frames used A/B, skipped incomplete C/D, undecodable E, ...".
struct HandExitLine {
  std::uint64_t used[2] = {0, 0};
  std::uint64_t skipped_incomplete[2] = {0, 0};
  std::uint64_t undecodable = 0;
};
std::optional<HandExitLine> hand_node_exit_line(const std::string& log);

// Lines of `log` containing `part`.
std::size_t count_lines(const std::string& log, const std::string& part);

}  // namespace tactile::faults
