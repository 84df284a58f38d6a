#pragma once

// One camera's pipeline: frames from the camera seam, the measurement core, TactileFrames out.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "sensor_config.hpp"
#include "tactile/camera/camera.hpp"
#include "tactile/extractor.hpp"
#include "tactile/util/repeat_limiter.hpp"
#include "tactile/v1/log.pb.h"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/sockets.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::sensor {

// One PUB socket shared by every camera thread (a ZeroMQ socket must not be used by two threads
// at once; the lock is held only for the send).
// With raw frames, messages kept for each subscriber that falls behind. A recorder of raw frames
// (300 KB each at 640 x 480) falls seconds behind on a loaded machine; with ZeroMQ's default of
// 1000 messages (1.2 s of two cameras at 200 fps) run-system's recordings lost runs of 40 to 300
// frames mid-run. 5000 is about 6 s of that, and at most about 750 MB held for one subscriber
// that stops reading altogether.
inline constexpr int kRawFramesSendQueue = 5000;

class SharedPublisher {
 public:
  SharedPublisher(zmq::context_t& ctx, const std::string& endpoint,
                  const wire::ServerSecurity* security, int send_queue)
      : pub_(ctx, endpoint, security, send_queue) {}
  void send(std::string_view topic, std::span<const std::uint8_t> payload) {
    std::lock_guard lock(mutex_);
    pub_.send(topic, payload);
  }
  std::string endpoint() const { return pub_.endpoint(); }

 private:
  std::mutex mutex_;
  wire::Publisher pub_;
};

// Times of the last interval, fixed capacity: the per-frame path records without allocating.
class IntervalTimes {
 public:
  void add(double us) noexcept {
    if (n_ < values_.size()) values_[n_++] = us;
    max_ = std::max(max_, us);
  }
  // Median and maximum of the interval, then starts a new one.
  std::pair<double, double> take() noexcept;

 private:
  std::array<double, 8192> values_{};
  std::size_t n_ = 0;
  double max_ = 0;
};

struct PipelineCounters {
  std::atomic<std::uint64_t> published{0};
  std::atomic<std::uint64_t> complete{0};
  std::atomic<std::uint64_t> not_measured{0};
  std::atomic<std::uint64_t> camera_restarts{0};
};

class Pipeline {
 public:
  Pipeline(CameraConfig cfg, const ExtractorOptions& measurement, double stats_period_s,
           bool raw_frames, std::unique_ptr<camera::Camera> cam, SharedPublisher& pub);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;
  // Runs until `stop` is set: opens the camera (retrying with backoff), takes or loads the
  // reference, then measures and publishes every frame. Never throws.
  void run(const std::atomic<bool>& stop) noexcept;
  const PipelineCounters& counters() const { return counters_; }
  // The last error that kept the pipeline from running (for the program's exit message).
  const std::string& fatal_error() const { return fatal_; }

 private:
  bool connect(const std::atomic<bool>& stop, bool initial);
  bool load_reference();
  void publish(const camera::Frame& frame, v1::FrameStatus status, double measure_us);
  void publish_stats();
  // The reference in use becomes exactly the rounded image it is saved as (so a restart, a
  // recording and a replay all measure with the same one); then it is announced.
  void reference_in_use();
  void publish_reference();
  // Writes the reference to reference_cache on a thread of its own: the write ends with an
  // fsync that can take tens of milliseconds, and frames arriving meanwhile are measured when
  // they arrive, not after it. A failed write is a warning (a restart then captures again).
  void save_reference();
  void publish_raw(const camera::Frame& frame, std::uint64_t tactile_sequence, bool forgot);
  void wait(double seconds, const std::atomic<bool>& stop) const;

  CameraConfig cfg_;
  Extractor extractor_;
  std::unique_ptr<camera::Camera> cam_;
  SharedPublisher& pub_;
  double stats_period_s_;
  bool raw_frames_ = false;
  v1::RawFrame raw_;  // reused: its pixel buffer keeps its capacity
  std::string raw_bytes_;
  std::string raw_topic_;
  bool capturing_reference_ = false;
  util::RepeatLimiter refusals_;  // the reference's refusals, once a second
  // The core was told to forget the previous frame since the last measured one (a replay must
  // do the same: docs/recording.md).
  bool forgot_pending_ = true;

  v1::Envelope env_;
  v1::Envelope stats_env_;  // its own: switching one envelope's body would free the frame's
  std::string bytes_;
  std::string topic_;
  std::string stats_topic_;
  std::uint64_t sequence_ = 0;
  IntervalTimes measure_times_;
  IntervalTimes publish_times_;
  std::int64_t last_stats_ns_ = 0;
  PipelineCounters counters_;
  Region region_;  // the last whole frame's part of the sensor image (SensorStats.region)
  std::string fatal_;
  std::thread saver_;  // the reference being written, if any
};

}  // namespace tactile::sensor
