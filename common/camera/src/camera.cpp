#include "tactile/camera/camera.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <stdexcept>

namespace tactile::camera {

std::string_view to_string(FrameStatus status) {
  switch (status) {
    case FrameStatus::kComplete:
      return "complete";
    case FrameStatus::kMissingPackets:
      return "missing packets";
    case FrameStatus::kSizeMismatch:
      return "size mismatch";
    case FrameStatus::kTimeout:
      return "timeout";
    case FrameStatus::kWrongFormat:
      return "wrong format";
    case FrameStatus::kAborted:
      return "aborted";
    case FrameStatus::kCameraError:
      return "camera error";
  }
  return "camera error";
}

std::string_view to_string(PixelFormat format) {
  return format == PixelFormat::kMono8 ? "Mono8" : "Mono16";
}

PixelFormat parse_pixel_format(std::string_view text) {
  if (text == "Mono8") return PixelFormat::kMono8;
  if (text == "Mono16") return PixelFormat::kMono16;
  throw std::invalid_argument(
      fmt::format("pixel format '{}' is not supported: use Mono8 or Mono16", text));
}

std::string to_string(const FrameFormat& format) {
  return fmt::format("{}x{} {}", format.width, format.height, to_string(format.pixel_format));
}

namespace {
// GigE Vision 1.x block ids: 1..65535, then 1 again.
constexpr std::uint64_t kBlockIdModulus = 65535;
}  // namespace

FrameSequencer::Step FrameSequencer::next(std::uint64_t camera_frame_id) {
  Step step;
  if (!running_) {
    step.first_after_start = true;
    step.sequence = started_ever_ ? last_sequence_ + 1 : 0;
    running_ = true;
    started_ever_ = true;
    last_id_ = camera_frame_id;
    last_sequence_ = step.sequence;
    return step;
  }

  std::uint64_t forward = 0;
  std::uint64_t backward = 0;
  const bool sixteen_bit =
      camera_frame_id != 0 && last_id_ != 0 && camera_frame_id <= 0xFFFF && last_id_ <= 0xFFFF;
  if (sixteen_bit) {
    const std::uint64_t a = camera_frame_id - 1;
    const std::uint64_t b = last_id_ - 1;
    const std::uint64_t diff = (a + kBlockIdModulus - b) % kBlockIdModulus;
    if (diff == 0) {
      backward = 0;
    } else if (diff <= kBlockIdModulus / 2) {
      forward = diff;
    } else {
      backward = kBlockIdModulus - diff;
    }
  } else if (camera_frame_id > last_id_) {
    forward = camera_frame_id - last_id_;
  } else {
    backward = last_id_ - camera_frame_id;
  }

  if (forward == 0) {
    // A repeated or reordered frame: its own (earlier) place, and no change of state.
    step.late = true;
    step.repeated = backward == 0;
    step.sequence = last_sequence_ - std::min(backward, last_sequence_);
    return step;
  }
  step.sequence = last_sequence_ + forward;
  step.frames_lost = forward - 1;
  last_id_ = camera_frame_id;
  last_sequence_ = step.sequence;
  return step;
}

ReconnectPolicy::ReconnectPolicy(ReconnectOptions options, std::int64_t now_ns)
    : options_(options),
      last_alive_ns_(now_ns),
      next_attempt_ns_(now_ns),
      backoff_ns_(options.initial_backoff.count()) {
  if (options_.stale_after.count() <= 0) {
    throw std::invalid_argument(fmt::format("reconnect option stale_after = {} ns: must be > 0",
                                            options_.stale_after.count()));
  }
  if (options_.initial_backoff.count() <= 0) {
    throw std::invalid_argument(fmt::format("reconnect option initial_backoff = {} ns: must be > 0",
                                            options_.initial_backoff.count()));
  }
  if (options_.max_backoff < options_.initial_backoff) {
    throw std::invalid_argument(
        fmt::format("reconnect option max_backoff = {} ns: must be >= initial_backoff ({} ns)",
                    options_.max_backoff.count(), options_.initial_backoff.count()));
  }
  if (!(options_.backoff_factor >= 1.0 && options_.backoff_factor <= 100.0)) {
    throw std::invalid_argument(fmt::format(
        "reconnect option backoff_factor = {}: must be in 1..100", options_.backoff_factor));
  }
}

void ReconnectPolicy::on_frame(std::int64_t now_ns) {
  last_alive_ns_ = now_ns;
  next_attempt_ns_ = now_ns;
  backoff_ns_ = options_.initial_backoff.count();
  failed_attempts_ = 0;
}

bool ReconnectPolicy::reopen_due(std::int64_t now_ns) const {
  return now_ns - last_alive_ns_ >= options_.stale_after.count() && now_ns >= next_attempt_ns_;
}

void ReconnectPolicy::on_reopen(bool succeeded, std::int64_t now_ns) {
  if (succeeded) {
    on_frame(now_ns);
    return;
  }
  ++failed_attempts_;
  next_attempt_ns_ = now_ns + backoff_ns_;
  const double grown = static_cast<double>(backoff_ns_) * options_.backoff_factor;
  const auto max_ns = options_.max_backoff.count();
  backoff_ns_ = grown >= static_cast<double>(max_ns) ? max_ns : static_cast<std::int64_t>(grown);
}

}  // namespace tactile::camera
