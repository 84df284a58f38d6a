#include "tactile/camera/replay_camera.hpp"

#include <fmt/core.h>

#include <cerrno>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "tactile/util/clock.hpp"
#include "tactile/util/pgm.hpp"

namespace tactile::camera {

namespace {

FrameFormat format_of(const Image& image) {
  return {image.width(), image.height(), image.format()};
}

// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (the pace of a file camera).
void sleep_until_monotonic(std::int64_t deadline_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline_ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(deadline_ns % 1000000000LL);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

void ReplayCameraOptions::validate() const {
  if (files.empty()) {
    throw std::invalid_argument("replay camera option files = []: give at least one PGM file");
  }
  if (!(frame_rate_hz > 0.0 && frame_rate_hz <= 100000.0)) {
    throw std::invalid_argument(fmt::format(
        "replay camera option frame_rate_hz = {}: must be in (0, 100000]", frame_rate_hz));
  }
  if (expected_format && (expected_format->width < 1 || expected_format->height < 1)) {
    throw std::invalid_argument(
        fmt::format("replay camera option expected_format = {}: width and height must be positive",
                    to_string(*expected_format)));
  }
}

struct ReplayCamera::Impl {
  explicit Impl(ReplayCameraOptions o) : options(std::move(o)) {
    options.validate();
    period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.frame_rate_hz));
  }

  ReplayCameraOptions options;
  FrameFormat frame_format;
  std::int64_t period_ns = 0;
  std::vector<Image> images;  // every file (preload), or the one being served
  bool opened = false;
  bool started = false;
  bool done = false;
  std::size_t next_file = 0;
  std::uint64_t served_since_start = 0;  // frames served since start(): the pace and timestamps
  std::uint64_t served_total = 0;        // frames served since open(): the frame ids
  std::int64_t start_monotonic_ns = 0;
  std::int64_t start_timestamp_ns = 0;
  FrameSequencer sequencer;
  CameraCounters counted;
  std::string last_error;

  void open() {
    if (opened) return;
    images.clear();
    if (options.preload) {
      images.reserve(options.files.size());
      for (const auto& file : options.files)
        images.push_back(util::read_pgm(file));
    } else {
      images.push_back(util::read_pgm(options.files.front()));
    }
    frame_format = options.expected_format ? *options.expected_format : format_of(images.front());
    opened = true;
  }

  void start() {
    open();
    if (started) return;
    sequencer.restart();
    served_since_start = 0;
    start_monotonic_ns = util::monotonic_ns();
    start_timestamp_ns =
        options.start_timestamp_ns ? *options.start_timestamp_ns : util::realtime_ns();
    started = true;
  }

  Frame wait(Duration timeout) noexcept {
    Frame frame;
    if (!started) {
      frame.status = FrameStatus::kCameraError;
      return frame;
    }
    if (done) return frame;
    if (options.paced) {
      const std::int64_t due =
          start_monotonic_ns + static_cast<std::int64_t>(served_since_start) * period_ns;
      const std::int64_t now = util::monotonic_ns();
      if (due > now + timeout.count()) {
        sleep_until_monotonic(now + std::max<std::int64_t>(timeout.count(), 0));
        ++counted.wait_timeouts;
        return frame;
      }
      if (due > now) sleep_until_monotonic(due);
    }

    const std::size_t index = next_file;
    const Image* image = nullptr;
    if (options.preload) {
      image = &images[index];
    } else {
      try {
        images.front() = util::read_pgm(options.files[index]);
        image = &images.front();
      } catch (const std::exception& e) {
        last_error = e.what();
      }
    }

    frame.received = true;
    frame.camera_frame_id = served_total + 1;
    frame.camera_timestamp_ns =
        start_timestamp_ns + static_cast<std::int64_t>(served_since_start) * period_ns;
    frame.receive_timestamp_ns = util::realtime_ns();
    const FrameSequencer::Step step = sequencer.next(frame.camera_frame_id);
    frame.sequence = step.sequence;
    frame.first_after_start = step.first_after_start;
    if (image == nullptr) {
      frame.status = FrameStatus::kCameraError;
    } else if (format_of(*image) != frame_format) {
      frame.status = FrameStatus::kWrongFormat;
    } else {
      frame.status = FrameStatus::kComplete;
      frame.image = image->view();
    }
    ++counted.frames;
    if (frame.status == FrameStatus::kComplete) {
      ++counted.completed;
    } else {
      ++counted.incomplete;
    }

    ++served_since_start;
    ++served_total;
    if (++next_file == options.files.size()) {
      next_file = 0;
      done = !options.loop;
    }
    return frame;
  }
};

ReplayCamera::ReplayCamera(ReplayCameraOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

ReplayCamera::~ReplayCamera() = default;

void ReplayCamera::open() {
  impl_->open();
}

void ReplayCamera::start() {
  impl_->start();
}

void ReplayCamera::stop() noexcept {
  impl_->started = false;
}

bool ReplayCamera::reopen() noexcept {
  impl_->started = false;
  impl_->done = false;
  impl_->next_file = 0;
  try {
    impl_->start();
  } catch (const std::exception& e) {
    impl_->last_error = e.what();
    return false;
  }
  ++impl_->counted.reopens;
  return true;
}

const std::string& ReplayCamera::last_error() const noexcept {
  return impl_->last_error;
}

Frame ReplayCamera::wait_frame(Duration timeout) noexcept {
  return impl_->wait(timeout);
}

void ReplayCamera::release_frame() noexcept {}

CameraCounters ReplayCamera::counters() const noexcept {
  return impl_->counted;
}

const FrameFormat& ReplayCamera::format() const noexcept {
  return impl_->frame_format;
}

Duration ReplayCamera::nominal_period() const noexcept {
  return Duration(impl_->period_ns);
}

std::string ReplayCamera::describe() const {
  return fmt::format("replay of {} file(s) from {}: {} at {} fps{}{}", impl_->options.files.size(),
                     impl_->options.files.front().string(), to_string(impl_->frame_format),
                     impl_->options.frame_rate_hz, impl_->options.paced ? ", paced" : "",
                     impl_->options.loop ? ", looping" : "");
}

bool ReplayCamera::finished() const noexcept {
  return impl_->done;
}

}  // namespace tactile::camera
