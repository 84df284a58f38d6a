#pragma once

// A GigE Vision camera simulated in this process (Aravis's ArvGvFakeCamera) that sends the
// images a renderer publishes: the rig's cameras. It speaks real GVCP and GVSP on its own IPv4
// address, so sensor_node (and arv-tool-0.8) talk to it as to a real camera.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "tactile/camera/camera.hpp"

namespace tactile::camera {

struct FakeGvCameraOptions {
  // IPv4 address to serve on (GVCP port 3956): it must be assigned to an interface (only
  // 127.0.0.1 is on a stock machine; see docs/camera.md for 127.0.0.2 and 127.0.0.3).
  std::string address = "127.0.0.2";
  std::string serial = "GV01";  // 1 to 15 characters
  // The camera's power-on format and rate; width x height is its sensor. A receiver may change
  // them over GVCP (AravisCamera sets its own) and set a region of interest inside the sensor
  // (OffsetX, OffsetY, Width, Height), whose part of the published image the camera then sends.
  // A frame whose pixel format differs from format()'s, or whose region leaves the sensor, is
  // sent without the published image (its content is then undefined) and reported with
  // SentFrame::format_matched false.
  int width = 640;
  int height = 480;
  PixelFormat pixel_format = PixelFormat::kMono8;
  double frame_rate_hz = 100.0;  // 0.1 to 1000
  // Probability that each GVSP packet is dropped instead of sent (fault injection), 0..1.
  double gvsp_lost_ratio = 0.0;

  // Throws std::invalid_argument naming the first bad option and its value.
  void validate() const;
};

// One frame as the camera sent it: how ground truth is matched to what a receiver gets.
struct SentFrame {
  // The frame id and timestamp the renderer published with the image (0 and 0 before the
  // first publish). The receiver sees `timestamp_ns` exactly as its camera timestamp.
  std::uint64_t frame_id = 0;
  std::int64_t timestamp_ns = 0;
  // The GigE Vision block id the camera stamped on it (the receiver's camera_frame_id).
  std::uint64_t block_id = 0;
  // CLOCK_REALTIME when the camera copied the image into its buffer, just before sending.
  std::int64_t fill_time_ns = 0;
  // The part of the published image the frame holds: the region of interest a receiver set
  // (OffsetX, OffsetY, Width, Height; the whole image by default).
  int origin_x = 0;
  int origin_y = 0;
  int width = 0;
  int height = 0;
  // False when the camera's pixel format differs from format()'s, or its region does not lie
  // inside format()'s image: the image was not sent.
  bool format_matched = true;
  // The inter-packet delay a receiver set (GevSCPD, converted to ns with the camera's 1 GHz tick
  // frequency): the frame's packets leave at least this far apart. 0: back to back.
  std::int64_t packet_delay_ns = 0;
  // The camera's previous frame (block_id - 1, when it sent one): the time between its packets,
  // from the end of each send to the start of the next, summed. With a packet delay it is at
  // least (packets - 1) x the delay, however busy the machine; back to back, the send loop's own.
  std::int64_t previous_frame_packet_gaps_ns = 0;
};

class FakeGvCamera {
 public:
  // Starts serving at once. Throws std::runtime_error when the camera cannot serve on the
  // address (not assigned to an interface, or port 3956 taken), saying how to fix it.
  explicit FakeGvCamera(FakeGvCameraOptions options);
  ~FakeGvCamera();
  FakeGvCamera(const FakeGvCamera&) = delete;
  FakeGvCamera& operator=(const FakeGvCamera&) = delete;

  bool is_running() const noexcept;
  const FakeGvCameraOptions& options() const noexcept;
  // The format of the images publish() accepts (the options' width, height, pixel format).
  FrameFormat format() const noexcept;

  // Makes `image` the one the camera sends from its next frame on, with the frame id and
  // timestamp it belongs to. One copy into a double buffer; the camera thread copies the
  // latest published image into each frame it sends, so a frame is sent again when nothing
  // newer was published, and a publish between two frames replaces the previous one unsent.
  // Returns false (and publishes nothing) when the image's format differs from format().
  // Thread-safe; one renderer thread at a time.
  [[nodiscard]] bool publish(const ImageView& image, std::uint64_t frame_id,
                             std::int64_t timestamp_ns) noexcept;

  // Fault injection: the probability each stream packet is dropped. Throws
  // std::invalid_argument outside 0..1.
  void set_gvsp_lost_ratio(double ratio);
  double gvsp_lost_ratio() const noexcept;

  // Called on the camera thread for every frame, after the copy and before its packets are
  // sent. Keep it short: that thread also answers GVCP. An exception it throws is swallowed
  // (it cannot cross Aravis's C code). Replaces any previous observer.
  using SentObserver = std::function<void(const SentFrame&)>;
  void set_sent_observer(SentObserver observer);
  SentFrame last_sent() const noexcept;
  std::uint64_t frames_sent() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tactile::camera
