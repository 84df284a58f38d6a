#pragma once

// A camera that serves a list of binary PGM files (Mono8 or Mono16) as frames, in order: for
// tools and tests.
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "tactile/camera/camera.hpp"

namespace tactile::camera {

struct ReplayCameraOptions {
  std::vector<std::filesystem::path> files;
  // Nominal rate: frame k's camera timestamp is the start time + k periods.
  double frame_rate_hz = 100.0;
  // True: frame k is served no earlier than k periods after start() (wait_frame blocks until
  // then, within its timeout). False: every wait_frame serves the next file at once.
  bool paced = true;
  // Start again with the first file after the last one (frame ids and sequence keep counting).
  bool loop = false;
  // Every frame must have this format; files that differ are served with kWrongFormat. Unset:
  // the first file sets the format.
  std::optional<FrameFormat> expected_format;
  // True: read every file at open() (frames are then served without reading or allocating;
  // memory is the sum of the images). False: read each file when it is served (for long
  // recordings; a file that cannot be read then is served as kCameraError).
  bool preload = true;
  // Camera timestamp of frame 0 (ns); unset: CLOCK_REALTIME at start().
  std::optional<std::int64_t> start_timestamp_ns;

  // Throws std::invalid_argument naming the first bad option and its value.
  void validate() const;
};

class ReplayCamera final : public Camera {
 public:
  explicit ReplayCamera(ReplayCameraOptions options);
  ~ReplayCamera() override;

  // Reads the files (preload) or the first one; throws std::runtime_error naming a file that
  // cannot be read.
  void open() override;
  void start() override;
  void stop() noexcept override;
  // Starts again from the first file.
  bool reopen() noexcept override;
  const std::string& last_error() const noexcept override;

  // After the last file (without loop): returns at once with received == false.
  Frame wait_frame(Duration timeout) noexcept override;
  void release_frame() noexcept override;

  CameraCounters counters() const noexcept override;
  const FrameFormat& format() const noexcept override;
  Duration nominal_period() const noexcept override;
  std::string describe() const override;

  // True once every file has been served (never with loop).
  bool finished() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tactile::camera
