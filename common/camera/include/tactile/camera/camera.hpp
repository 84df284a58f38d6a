#pragma once

// The camera seam of sensor_node: one narrow interface in front of every source of frames (a
// GigE Vision camera through Aravis, a list of image files). No Aravis type appears here.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "tactile/image.hpp"

namespace tactile::camera {

// Why a frame is or is not whole. The numbers are those of tactile.v1.FrameStatus on the wire
// (proto/tactile/v1/tactile.proto), so converting is a cast; a unit test holds them equal.
enum class FrameStatus : std::uint8_t {
  kComplete = 1,        // every byte arrived and the frame has the configured format
  kMissingPackets = 2,  // the camera delivered an incomplete frame
  kSizeMismatch = 3,    // the payload size differs from width * height * bytes per pixel
  kTimeout = 4,         // the frame timed out, or no frame came within the wait
  kWrongFormat = 5,     // pixel format or geometry differs from the configured one
  kAborted = 6,         // acquisition stopped while the frame was being received
  kCameraError = 8,     // any other failure of the camera or the transport
};

std::string_view to_string(FrameStatus status);

// A camera that answers but cannot take what was asked (an image larger than its sensor, a pixel
// format or region it refuses or rounds): a configuration error, not a camera that may come back.
// Programs stop at start-up on it instead of retrying.
class CameraRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a camera delivers: fixed at open(), checked on every frame.
struct FrameFormat {
  int width = 0;
  int height = 0;
  PixelFormat pixel_format = PixelFormat::kMono8;

  std::size_t payload_bytes() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
           bytes_per_pixel(pixel_format);
  }
  friend bool operator==(const FrameFormat&, const FrameFormat&) = default;
};

std::string to_string(const FrameFormat& format);
// "Mono8" or "Mono16" (GenICam names); parse_pixel_format throws std::invalid_argument otherwise.
std::string_view to_string(PixelFormat format);
PixelFormat parse_pixel_format(std::string_view text);

// One result of Camera::wait_frame.
struct Frame {
  FrameStatus status = FrameStatus::kTimeout;
  // False when no frame came: status kTimeout after the wait, or kCameraError at once when the
  // camera is not started (or was given up). Nothing else below is set then.
  bool received = false;
  // True for the first frame after start() or reopen(): the gap to the previous frame is unknown.
  bool first_after_start = false;
  // The pixels; set only when status is kComplete. Valid until release_frame(), the next
  // wait_frame(), stop() or the camera's destruction, whichever comes first.
  ImageView image;
  // The camera's own frame (GigE Vision block) id as delivered: 16-bit and wrapping on
  // GigE Vision 1.x, where 0 is never used. 0 here: the id is unknown (the frame's leader was
  // lost); such a frame is never complete and has sequence 0 and frames_lost 0.
  std::uint64_t camera_frame_id = 0;
  // Unwrapped frame counter: +1 per frame the camera sent, lost ones included, so a step of k
  // between two received frames means k frame periods. Keeps counting across reopen(). An
  // incomplete frame may come after a newer one (its packets were waited for longer): its
  // sequence is then below the previous frame's.
  std::uint64_t sequence = 0;
  // Frames the camera sent between the newest frame received before and this one, not received
  // (yet): the sequence step minus one; 0 when first_after_start or for a late frame.
  std::uint64_t frames_lost = 0;
  // The camera's timestamp of the frame (ns; the camera's clock).
  std::int64_t camera_timestamp_ns = 0;
  // CLOCK_REALTIME (ns) when the last packet of the frame was received.
  std::int64_t receive_timestamp_ns = 0;
};

// Monotonic counters since the camera object was made (they survive reopen()).
struct CameraCounters {
  std::uint64_t frames = 0;           // frames delivered by wait_frame (received == true)
  std::uint64_t completed = 0;        // of which kComplete
  std::uint64_t incomplete = 0;       // of which any other status
  std::uint64_t frames_lost = 0;      // frames the camera sent that never arrived (id gaps)
  std::uint64_t wait_timeouts = 0;    // waits that ended with no frame
  std::uint64_t underruns = 0;        // transport had no free buffer for a frame
  std::uint64_t missing_packets = 0;  // packets of incomplete frames that never arrived
  std::uint64_t failures = 0;         // frames the transport closed with an error status
  std::uint64_t reopens = 0;          // successful reopen() calls
};

using Duration = std::chrono::nanoseconds;

// A source of frames. One thread drives a Camera (open, start, wait_frame, release_frame, stop,
// counters); implementations may receive on their own threads behind it.
//
// Errors: configuration and connection errors throw (std::invalid_argument for a bad option,
// naming it and its value; std::runtime_error for a camera that cannot be reached or set up).
// wait_frame, release_frame and counters never throw and, once started, never allocate.
class Camera {
 public:
  virtual ~Camera() = default;
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  // Connects and configures the camera. Throws on any failure.
  virtual void open() = 0;
  // Starts acquisition (opens first if needed). Throws on failure.
  virtual void start() = 0;
  // Stops acquisition and takes back every buffer. Never throws; safe to call twice.
  virtual void stop() noexcept = 0;
  // Tears everything down and opens and starts again, for a camera that stopped delivering.
  // Returns false, with last_error() set, when the camera cannot be reached yet.
  virtual bool reopen() noexcept = 0;
  virtual const std::string& last_error() const noexcept = 0;

  // Waits at most `timeout` for the next frame. Releases the previous frame first.
  virtual Frame wait_frame(Duration timeout) noexcept = 0;
  // Returns the frame's buffer to the camera early (optional: wait_frame does it too).
  virtual void release_frame() noexcept = 0;

  virtual CameraCounters counters() const noexcept = 0;
  // The format every complete frame has; valid after open().
  virtual const FrameFormat& format() const noexcept = 0;
  // Nominal frame period (1 / configured frame rate).
  virtual Duration nominal_period() const noexcept = 0;
  // A one-line description for logs ("GigE Vision 127.0.0.2 (serial GV01) 640x480 Mono8 ...").
  virtual std::string describe() const = 0;

 protected:
  Camera() = default;
};

// Unwraps camera frame ids into a 64-bit sequence. GigE Vision 1.x block ids run 1..65535 and
// wrap to 1 (0 is never used); ids above 65535 (64-bit block ids) are taken as they are.
// Pure; used by every Camera implementation.
class FrameSequencer {
 public:
  struct Step {
    std::uint64_t sequence = 0;
    std::uint64_t frames_lost = 0;
    bool first_after_start = false;
    bool late = false;      // an id not newer than the newest seen: reordered or repeated
    bool repeated = false;  // the newest id again
  };

  // The next received frame's id. After restart() the first id starts a new run: its
  // sequence is the previous one + 1.
  Step next(std::uint64_t camera_frame_id);
  void restart() { running_ = false; }

 private:
  bool running_ = false;
  bool started_ever_ = false;
  std::uint64_t last_id_ = 0;
  std::uint64_t last_sequence_ = 0;
};

// When to reopen a camera that stopped delivering, with exponential backoff between failed
// attempts. Pure: time is an argument (monotonic ns).
struct ReconnectOptions {
  Duration stale_after = std::chrono::seconds(1);  // no frame for this long: reopen
  Duration initial_backoff = std::chrono::milliseconds(200);
  Duration max_backoff = std::chrono::seconds(5);
  double backoff_factor = 2.0;
};

class ReconnectPolicy {
 public:
  // Throws std::invalid_argument naming the option for non-positive durations, a factor
  // below 1, or max_backoff below initial_backoff.
  explicit ReconnectPolicy(ReconnectOptions options, std::int64_t now_ns);

  // Any received frame (whatever its status) proves the camera alive.
  void on_frame(std::int64_t now_ns);
  // True when the caller should call reopen() now.
  bool reopen_due(std::int64_t now_ns) const;
  void on_reopen(bool succeeded, std::int64_t now_ns);

  Duration current_backoff() const { return Duration(backoff_ns_); }
  int failed_attempts() const { return failed_attempts_; }

 private:
  ReconnectOptions options_;
  std::int64_t last_alive_ns_;
  std::int64_t next_attempt_ns_;
  std::int64_t backoff_ns_;
  int failed_attempts_ = 0;
};

}  // namespace tactile::camera
