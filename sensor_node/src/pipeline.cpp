#include "pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/pgm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/raw_frame.hpp"

namespace tactile::sensor {
namespace {

v1::FrameStatus to_wire(camera::FrameStatus s) {
  // The camera seam numbers its statuses as the wire does (a camera test holds them equal).
  return static_cast<v1::FrameStatus>(static_cast<int>(s));
}

}  // namespace

std::pair<double, double> IntervalTimes::take() noexcept {
  double median = 0;
  if (n_ > 0) {
    std::nth_element(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(n_ / 2),
                     values_.begin() + static_cast<std::ptrdiff_t>(n_));
    median = values_[n_ / 2];
  }
  const std::pair<double, double> r{median, max_};
  n_ = 0;
  max_ = 0;
  return r;
}

Pipeline::Pipeline(CameraConfig cfg, const ExtractorOptions& measurement, double stats_period_s,
                   bool raw_frames, std::unique_ptr<camera::Camera> cam, SharedPublisher& pub)
    : cfg_(std::move(cfg)),
      extractor_(cfg_.calibration, measurement),
      cam_(std::move(cam)),
      pub_(pub),
      stats_period_s_(stats_period_s),
      raw_frames_(raw_frames),
      raw_topic_(wire::raw_topic(cfg_.sensor_id)),
      topic_(wire::frame_topic(cfg_.sensor_id)),
      stats_topic_(wire::stats_topic(cfg_.sensor_id)) {}

void Pipeline::wait(double seconds, const std::atomic<bool>& stop) const {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!stop && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

bool Pipeline::connect(const std::atomic<bool>& stop, bool initial) {
  double backoff = cfg_.retry_initial_s;
  // start() opens a camera the first time; after a failure only reopen() tears it down first.
  bool first = initial;
  while (!stop) {
    bool ok = false;
    std::string why;
    if (first) {
      try {
        cam_->start();
        ok = true;
      } catch (const camera::CameraRefused& e) {
        // It answered and refused: waiting will not change it.
        throw std::runtime_error(fmt::format(
            "{}; the calibration {} is for {}x{} {} images: calibrate this camera, or use one "
            "that takes the calibration's image",
            e.what(), cfg_.calibration_path.string(), cfg_.calibration.width,
            cfg_.calibration.height, camera::to_string(cfg_.camera.pixel_format)));
      } catch (const std::exception& e) {
        why = e.what();
      }
    } else {
      ok = cam_->reopen();
      why = cam_->last_error();
      if (ok) ++counters_.camera_restarts;
    }
    if (ok) {
      util::log_info("{}: camera {}", cfg_.sensor_id, cam_->describe());
      return true;
    }
    util::log_warn("{}: camera {} unavailable ({}); retrying in {:.1f} s", cfg_.sensor_id,
                   cfg_.camera.camera, why, backoff);
    first = false;
    wait(backoff, stop);
    backoff = std::min(backoff * 2, cfg_.retry_max_s);
  }
  return false;
}

bool Pipeline::load_reference() {
  std::filesystem::path file;
  if (!cfg_.reference.empty()) {
    file = cfg_.reference;
  } else if (!cfg_.reference_cache.empty() && std::filesystem::exists(cfg_.reference_cache)) {
    file = cfg_.reference_cache;
  } else {
    return false;
  }
  const Image img = util::read_pgm(file);  // throws with the file's name
  extractor_.begin_reference();
  const auto r = extractor_.add_reference_frame(img.view());
  const auto done = r.status == ReferenceStatus::kCollecting ? extractor_.finish_reference() : r;
  if (done.status != ReferenceStatus::kComplete) {
    throw std::runtime_error(file.string() + ": reference " + to_string(done.status) +
                             " (element " + std::to_string(done.element_id) + ")");
  }
  util::log_info("{}: reference loaded from {}", cfg_.sensor_id, file.string());
  forgot_pending_ = true;
  publish_reference();
  return true;
}

void Pipeline::publish(const camera::Frame& frame, v1::FrameStatus status, double measure_us) {
  wire::FrameHeader h;
  h.sequence = sequence_++;
  h.camera_frame_id = frame.camera_frame_id;
  h.camera_timestamp_ns = frame.camera_timestamp_ns;
  h.receive_timestamp_ns = frame.receive_timestamp_ns;
  h.status = status;
  h.nominal_period_ns = cam_->nominal_period().count();
  h.frames_skipped =
      static_cast<std::uint32_t>(std::min<std::uint64_t>(frame.frames_lost, UINT32_MAX));
  h.measure_time_us = measure_us;
  h.publish_timestamp_ns = util::realtime_ns();
  wire::fill_tactile_frame(cfg_.sensor_id, h, extractor_.readings(), cfg_.calibration.mm_per_px,
                           *env_.mutable_tactile_frame());
  wire::encode(env_, bytes_);
  pub_.send(topic_, wire::bytes_of(bytes_));
  ++counters_.published;
  if (frame.receive_timestamp_ns > 0) {
    publish_times_.add(static_cast<double>(util::realtime_ns() - frame.receive_timestamp_ns) *
                       1e-3);
  }
}

void Pipeline::reference_in_use() {
  // The captured mean has sub-gray-level precision no image file carries: use exactly the
  // rounded image that is saved and published instead.
  const Image rounded = extractor_.reference_image();
  extractor_.begin_reference();
  const ReferenceResult r = extractor_.add_reference_frame(rounded.view());
  if (r.status == ReferenceStatus::kCollecting) extractor_.finish_reference();
  publish_reference();
}

void Pipeline::save_reference() {
  if (cfg_.reference_cache.empty()) return;
  if (saver_.joinable()) saver_.join();  // a previous capture's write (a reopen)
  saver_ = std::thread([path = cfg_.reference_cache, id = cfg_.sensor_id,
                        pgm = util::encode_pgm(extractor_.reference_image().view())] {
    try {
      util::write_file_atomic(path, pgm);
      util::log_info("{}: reference saved to {}", id, path.string());
    } catch (const std::exception& e) {
      util::log_warn("{}: reference not saved ({}); a restart will capture one again", id,
                     e.what());
    }
  });
}

void Pipeline::publish_reference() {
  if (!raw_frames_ || !extractor_.has_reference()) return;
  raw_.Clear();
  raw_.set_sensor_id(cfg_.sensor_id);
  raw_.set_kind(v1::RAW_FRAME_KIND_REFERENCE);
  wire::fill_raw_pixels(extractor_.reference_image().view(), raw_);
  wire::fill_settings(extractor_.options(), *raw_.mutable_settings());
  raw_.SerializeToString(&raw_bytes_);
  pub_.send(raw_topic_, wire::bytes_of(raw_bytes_));
}

void Pipeline::publish_raw(const camera::Frame& frame, std::uint64_t tactile_sequence,
                           bool forgot) {
  raw_.clear_settings();
  raw_.set_sensor_id(cfg_.sensor_id);
  raw_.set_kind(v1::RAW_FRAME_KIND_MEASURED);
  raw_.set_tactile_sequence(tactile_sequence);
  raw_.set_sequence(frame.sequence);
  raw_.set_camera_frame_id(frame.camera_frame_id);
  raw_.set_camera_timestamp_ns(frame.camera_timestamp_ns);
  raw_.set_receive_timestamp_ns(frame.receive_timestamp_ns);
  raw_.set_forget_previous(forgot);
  wire::fill_raw_pixels(frame.image, raw_);
  raw_.SerializeToString(&raw_bytes_);
  pub_.send(raw_topic_, wire::bytes_of(raw_bytes_));
}

void Pipeline::publish_stats() {
  const camera::CameraCounters c = cam_->counters();
  v1::SensorStats& s = *stats_env_.mutable_sensor_stats();
  s.set_sensor_id(cfg_.sensor_id);
  s.set_time_ns(util::realtime_ns());
  s.set_frames(c.frames);
  s.set_frames_complete(c.completed);
  s.set_frames_incomplete(c.incomplete);
  s.set_underruns(c.underruns);
  s.set_missing_packets(c.missing_packets);
  const auto [m50, mmax] = measure_times_.take();
  const auto [p50, pmax] = publish_times_.take();
  s.set_measure_us_p50(m50);
  s.set_measure_us_max(mmax);
  s.set_publish_us_p50(p50);
  s.set_publish_us_max(pmax);
  s.set_camera_restarts(counters_.camera_restarts);
  if (region_.width > 0) {
    v1::ImageRegion& r = *s.mutable_region();
    r.set_x(static_cast<std::uint32_t>(region_.x));
    r.set_y(static_cast<std::uint32_t>(region_.y));
    r.set_width(static_cast<std::uint32_t>(region_.width));
    r.set_height(static_cast<std::uint32_t>(region_.height));
  }
  wire::encode(stats_env_, bytes_);
  pub_.send(stats_topic_, wire::bytes_of(bytes_));
  publish_reference();  // again now and then: a recorder that joins late still gets it
  util::log_debug(
      "{}: frames {} complete {} incomplete {} lost {} underruns {}; measure p50 {:.1f} us max "
      "{:.1f} us",
      cfg_.sensor_id, c.frames, c.completed, c.incomplete, c.frames_lost, c.underruns, m50, mmax);
}

// A camera whose images the calibration does not fit never will: a configuration error, said once
// with both sizes, not a refusal on every frame.
static std::string wrong_size(const CameraConfig& cfg, const ImageView& image) {
  return fmt::format(
      "the camera sends {}x{} images (at x {} y {}); the calibration {} is for {}x{} images: "
      "calibrate this camera, or give it the calibration's image size",
      image.width, image.height, image.origin_x, image.origin_y, cfg.calibration_path.string(),
      cfg.calibration.width, cfg.calibration.height);
}

void Pipeline::run(const std::atomic<bool>& stop) noexcept {
  try {
    const bool have_reference = load_reference();
    if (!connect(stop, true)) return;
    if (!have_reference) {
      extractor_.begin_reference();
      capturing_reference_ = true;
      util::log_info("{}: capturing the no-load reference ({} frames): do not touch the sensor",
                     cfg_.sensor_id, extractor_.options().reference_frames);
    }
    const auto timeout = std::chrono::duration_cast<camera::Duration>(
        std::chrono::duration<double>(cfg_.frame_timeout_s));
    last_stats_ns_ = util::monotonic_ns();
    while (!stop) {
      // Before the wait, never between a frame and its TactileFrame: the counters sent then
      // count exactly the frames whose TactileFrames went out.
      const std::int64_t now = util::monotonic_ns();
      if (now - last_stats_ns_ >= static_cast<std::int64_t>(stats_period_s_ * 1e9)) {
        publish_stats();
        last_stats_ns_ = now;
      }
      const camera::Frame frame = cam_->wait_frame(timeout);
      if (!frame.received) {
        if (stop) break;
        util::log_warn("{}: no frame for {:.2f} s ({}): reopening the camera", cfg_.sensor_id,
                       cfg_.frame_timeout_s, camera::to_string(frame.status));
        extractor_.forget_previous();
        forgot_pending_ = true;
        if (!connect(stop, false)) break;
        continue;
      }
      if (frame.first_after_start) {
        extractor_.forget_previous();
        forgot_pending_ = true;
      }
      if (frame.status != camera::FrameStatus::kComplete) {
        ++counters_.not_measured;
        publish(frame, to_wire(frame.status), 0);
        continue;
      }
      region_ = {frame.image.origin_x, frame.image.origin_y, frame.image.width, frame.image.height};
      if (capturing_reference_) {
        const ReferenceResult r = extractor_.add_reference_frame(frame.image);
        if (r.status == ReferenceStatus::kComplete) {
          capturing_reference_ = false;
          util::log_info("{}: reference captured from {} frames", cfg_.sensor_id, r.frames);
          reference_in_use();
          forgot_pending_ = true;
          save_reference();
        } else if (r.status == ReferenceStatus::kWrongSize) {
          throw std::runtime_error(wrong_size(cfg_, frame.image));
        } else if (r.status != ReferenceStatus::kCollecting) {
          // A sensor touched while the reference is captured (or a camera whose image never
          // settles) is refused on every frame, each time with another element and excess G:
          // once a second, counted (the log's own limit sees each figure as a new line).
          const util::RepeatLimiter::Decision d =
              refusals_.offer(to_string(r.status), util::monotonic_ns());
          if (d.write) {
            util::log_warn("{}: reference {} (element {}, excess G {:.0f}); starting again{}",
                           cfg_.sensor_id, to_string(r.status), r.element_id, r.value,
                           util::repeated_suffix(d.held_back));
          }
        }
        ++counters_.not_measured;
        publish(frame, v1::FRAME_STATUS_NO_REFERENCE, 0);
        continue;
      }
      const std::int64_t t0 = util::monotonic_ns();
      const MeasureStatus ms =
          extractor_.measure(frame.image, {frame.sequence, frame.camera_timestamp_ns});
      const double us = static_cast<double>(util::monotonic_ns() - t0) * 1e-3;
      measure_times_.add(us);
      if (ms == MeasureStatus::kOk) {
        ++counters_.complete;
        publish(frame, v1::FRAME_STATUS_COMPLETE, us);
        if (raw_frames_) publish_raw(frame, sequence_ - 1, forgot_pending_);
        forgot_pending_ = false;
      } else if (ms == MeasureStatus::kWrongSize) {
        throw std::runtime_error(wrong_size(cfg_, frame.image));
      } else {
        ++counters_.not_measured;
        publish(frame, v1::FRAME_STATUS_WRONG_FORMAT, us);
      }
    }
  } catch (const std::exception& e) {
    fatal_ = cfg_.sensor_id + ": " + e.what();
    util::log_error("{}", fatal_);
  }
  cam_->stop();
  if (saver_.joinable()) saver_.join();
}

Pipeline::~Pipeline() {
  if (saver_.joinable()) saver_.join();
}

}  // namespace tactile::sensor
