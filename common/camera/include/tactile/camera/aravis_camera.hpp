#pragma once

// A GigE Vision camera received through Aravis 0.8 (docs/camera.md says which settings and why).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "tactile/calibration.hpp"
#include "tactile/camera/camera.hpp"

namespace tactile::camera {

struct AravisCameraOptions {
  // The camera: an IPv4 address (preferred: opened directly, with no discovery, through the
  // interface the kernel routes to it) or an Aravis device id such as "Aravis-Fake-GV01".
  std::string camera;
  // Local IPv4 address to receive on; empty: the kernel's source address for `camera`.
  // Only used when `camera` is an address.
  std::string interface_address;

  // The sensor's image (the calibration's size).
  int width = 640;
  int height = 480;
  PixelFormat pixel_format = PixelFormat::kMono8;
  // The part of the width x height image to receive (GenICam OffsetX, OffsetY, Width, Height):
  // grown at open() to the camera's increments (align_region), and the frames' views carry its
  // origin. Width 0: the whole image. open() throws when the camera does not take it.
  Region region{};
  double frame_rate_hz = 100.0;  // AcquisitionFrameRate

  // GVSP packet size in bytes, headers included: at most the MTU of the link (65000 suits lo,
  // 1500 or 9000 an Ethernet link). Range 576..65500.
  int packet_size_bytes = 65000;
  // The inter-packet delay (GevSCPD, in ticks of the camera's timestamp clock, written from
  // nanoseconds with its tick frequency): what a lab sets when several cameras share a link
  // behind a switch that drops their bursts. -1 leaves the camera's own setting; 0..10 ms.
  // open() throws when the camera cannot take it (each camera has its own range).
  std::int64_t packet_delay_ns = -1;
  // Receive socket buffer, fixed size (the kernel caps it at net.core.rmem_max).
  std::size_t socket_buffer_bytes = std::size_t{4} << 20;
  // Frame buffers in the pool, 2..64 (4 to 8 is right for sensor_node).
  int buffer_count = 6;
  // Ask the camera to resend lost packets (GigE Vision cameras support it, the fake does not).
  bool packet_resend = false;
  // How long the receiver waits for a missing packet before giving up on it (Aravis
  // packet-timeout), and how long it keeps an incomplete frame (frame-retention).
  Duration packet_timeout = std::chrono::milliseconds(20);
  Duration frame_retention = std::chrono::milliseconds(100);

  // Throws std::invalid_argument naming the first bad option and its value.
  void validate() const;
};

class AravisCamera final : public Camera {
 public:
  // Validates the options (throws std::invalid_argument); does not touch the network.
  explicit AravisCamera(AravisCameraOptions options);
  ~AravisCamera() override;

  void open() override;
  void start() override;
  void stop() noexcept override;
  // For an address: returns false at once (300 ms) while the camera does not answer GVCP,
  // keeping the old objects; otherwise tears down, opens and starts again.
  bool reopen() noexcept override;
  const std::string& last_error() const noexcept override;

  Frame wait_frame(Duration timeout) noexcept override;
  void release_frame() noexcept override;

  CameraCounters counters() const noexcept override;
  const FrameFormat& format() const noexcept override;
  Duration nominal_period() const noexcept override;
  std::string describe() const override;

  const AravisCameraOptions& options() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// True when a GigE Vision device at `ipv4_address` answers a GVCP register read within
// `timeout` (three tries). Cheap: use it to wait for a camera to come up. Aravis's own control
// requests take 2.5 s to give up, and tearing down the objects of a camera that is gone makes
// several of them, so AravisCamera::reopen() asks this first and changes nothing while the
// camera is silent.
bool gvcp_device_answers(const std::string& ipv4_address, Duration timeout) noexcept;

}  // namespace tactile::camera
