#include "tactile/camera/aravis_camera.hpp"

#include <arpa/inet.h>
#include <fmt/core.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "aravis_support.hpp"
#include "tactile/camera/private_network.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"

namespace tactile::camera {

namespace {

bool is_ipv4(const std::string& text) {
  in_addr address{};
  return inet_pton(AF_INET, text.c_str(), &address) == 1;
}

std::int64_t read_rmem_max() {
  std::ifstream file("/proc/sys/net/core/rmem_max");
  std::int64_t value = -1;
  file >> value;
  return file ? value : -1;
}

struct UdpSocket {
  int fd = -1;
  sockaddr_in local{};
};

bool same_local(const sockaddr_in& a, const sockaddr_in& b) {
  return a.sin_port == b.sin_port && a.sin_addr.s_addr == b.sin_addr.s_addr;
}

// This process's IPv4 UDP sockets with their local addresses. Aravis's API does not expose its
// sockets; they are found here. One getsockname per open descriptor: open and close only.
std::vector<UdpSocket> udp_sockets() {
  std::vector<UdpSocket> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    const std::string name = entry.path().filename().string();
    UdpSocket s;
    if (std::from_chars(name.data(), name.data() + name.size(), s.fd).ec != std::errc{}) continue;
    socklen_t length = sizeof(s.local);
    int type = 0;
    socklen_t type_length = sizeof(type);
    if (::getsockname(s.fd, reinterpret_cast<sockaddr*>(&s.local), &length) == 0 &&
        s.local.sin_family == AF_INET &&
        ::getsockopt(s.fd, SOL_SOCKET, SO_TYPE, &type, &type_length) == 0 && type == SOCK_DGRAM) {
      out.push_back(s);
    }
  }
  return out;
}

// Sizes the receive buffer of Aravis's stream socket (bound to `port`) now, rather than when the
// stream's first frame starts, which is how Aravis 0.8.26 applies its FIXED size: the first
// frame's packets then met the default buffer (about 200 KiB), and a 640x480 frame overflowed
// it. Returns false when no such socket was found or the size was refused.
bool size_stream_socket(std::uint16_t port, std::size_t bytes) {
  const auto sockets = udp_sockets();
  const auto it = std::find_if(sockets.begin(), sockets.end(),
                               [&](const UdpSocket& s) { return ntohs(s.local.sin_port) == port; });
  if (it == sockets.end()) return false;
  const int fd = it->fd;
  const int size = static_cast<int>(
      std::min<std::size_t>(bytes, static_cast<std::size_t>(std::numeric_limits<int>::max())));
  return ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, sizeof(size)) == 0;
}

guint to_microseconds(Duration d) {
  return static_cast<guint>(std::chrono::duration_cast<std::chrono::microseconds>(d).count());
}

FrameStatus map_buffer_status(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return FrameStatus::kComplete;
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return FrameStatus::kMissingPackets;
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return FrameStatus::kSizeMismatch;
    case ARV_BUFFER_STATUS_TIMEOUT:
      return FrameStatus::kTimeout;
    case ARV_BUFFER_STATUS_ABORTED:
      return FrameStatus::kAborted;
    case ARV_BUFFER_STATUS_UNKNOWN:
    case ARV_BUFFER_STATUS_CLEARED:
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
    case ARV_BUFFER_STATUS_FILLING:
    default:
      return FrameStatus::kCameraError;
  }
}

}  // namespace

bool gvcp_device_answers(const std::string& address, Duration timeout) noexcept {
  // Three tries share the time: a lost datagram is not a silent camera.
  const int tries = 3;
  const auto per_try_ms = std::max<std::int64_t>(
      1, std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count() / tries);
  sockaddr_in target{};
  target.sin_family = AF_INET;
  target.sin_port = htons(3956);
  if (inet_pton(AF_INET, address.c_str(), &target.sin_addr) != 1) return false;
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  bool answered = false;
  for (int attempt = 0; attempt < tries && !answered; ++attempt) {
    const auto request_id = static_cast<std::uint16_t>(0x7a00 + attempt);
    // GVCP READREG_CMD: key 0x42, flags "ack required", command 0x0080, 4 bytes of payload.
    const std::uint8_t request[12] = {0x42,
                                      0x01,
                                      0x00,
                                      0x80,
                                      0x00,
                                      0x04,
                                      static_cast<std::uint8_t>(request_id >> 8),
                                      static_cast<std::uint8_t>(request_id & 0xff),
                                      0x00,
                                      0x00,
                                      0x00,
                                      0x00};
    if (::sendto(fd, request, sizeof(request), 0, reinterpret_cast<const sockaddr*>(&target),
                 sizeof(target)) != static_cast<ssize_t>(sizeof(request))) {
      break;
    }
    const std::int64_t deadline = util::monotonic_ns() + per_try_ms * 1000000LL;
    for (;;) {
      const std::int64_t left_ms = (deadline - util::monotonic_ns()) / 1000000LL;
      if (left_ms <= 0) break;
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left_ms)) <= 0) break;
      std::uint8_t reply[64];
      const ssize_t n = ::recv(fd, reply, sizeof(reply), 0);
      // READREG_ACK (0x0081) to our request id.
      if (n >= 8 && reply[2] == 0x00 && reply[3] == 0x81 &&
          reply[6] == static_cast<std::uint8_t>(request_id >> 8) &&
          reply[7] == static_cast<std::uint8_t>(request_id & 0xff)) {
        answered = true;
        break;
      }
    }
  }
  ::close(fd);
  return answered;
}

void AravisCameraOptions::validate() const {
  auto bad = [](std::string_view option, const auto& value, std::string_view rule) {
    return std::invalid_argument(fmt::format("camera option {} = {}: {}", option, value, rule));
  };
  if (camera.empty()) throw bad("camera", "\"\"", "give an IPv4 address or an Aravis device id");
  if (!interface_address.empty() && !is_ipv4(interface_address)) {
    throw bad("interface_address", interface_address, "must be an IPv4 address");
  }
  if (width < 1 || width > 65535) throw bad("width", width, "must be in 1..65535");
  if (height < 1 || height > 65535) throw bad("height", height, "must be in 1..65535");
  if (region.width != 0) {
    const bool inside = region.x >= 0 && region.y >= 0 && region.width >= 1 && region.height >= 1 &&
                        region.x <= width - region.width && region.y <= height - region.height;
    if (!inside) {
      throw bad(
          "region",
          fmt::format("x {} y {} width {} height {}", region.x, region.y, region.width,
                      region.height),
          fmt::format("must lie inside the {}x{} image (width 0: the whole image)", width, height));
    }
  }
  if (!(frame_rate_hz > 0.0 && frame_rate_hz <= 100000.0)) {
    throw bad("frame_rate_hz", frame_rate_hz, "must be in (0, 100000]");
  }
  if (packet_size_bytes < 576 || packet_size_bytes > 65500) {
    throw bad("packet_size_bytes", packet_size_bytes,
              "must be in 576..65500 and at most the link MTU");
  }
  if (packet_delay_ns < -1 || packet_delay_ns > 10'000'000) {
    throw bad("packet_delay_ns", packet_delay_ns,
              "must be in 0..10000000 (10 ms), or -1 to leave the camera's own");
  }
  if (socket_buffer_bytes < 65536 || socket_buffer_bytes > (std::size_t{1} << 30)) {
    throw bad("socket_buffer_bytes", socket_buffer_bytes, "must be in 65536..1073741824");
  }
  if (buffer_count < 2 || buffer_count > 64) {
    throw bad("buffer_count", buffer_count, "must be in 2..64 (4 to 8 suits sensor_node)");
  }
  if (packet_timeout < std::chrono::microseconds(100) ||
      packet_timeout > std::chrono::seconds(10)) {
    throw bad("packet_timeout_ns", packet_timeout.count(), "must be in 100 us..10 s");
  }
  if (frame_retention < std::chrono::milliseconds(1) ||
      frame_retention > std::chrono::seconds(10)) {
    throw bad("frame_retention_ns", frame_retention.count(), "must be in 1 ms..10 s");
  }
}

struct AravisCamera::Impl {
  // Where the stream callback leaves the time a buffer was done, for the consumer to pick up.
  struct Slot {
    std::uint64_t frame_id = 0;
    std::int64_t done_ns = 0;
    bool stamped = false;
  };

  explicit Impl(AravisCameraOptions o) : options(std::move(o)) {
    options.validate();
    format = {options.width, options.height, options.pixel_format};
    nominal_period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.frame_rate_hz));
  }
  ~Impl() { close(); }

  // Declared first: destroyed last, after every Aravis object below.
  detail::AravisUse aravis;
  AravisCameraOptions options;
  FrameFormat format;  // the region received (set at open)
  int origin_x = 0;    // where the region's pixel (0, 0) lies on the sensor
  int origin_y = 0;
  std::int64_t nominal_period_ns = 0;
  std::string last_error;
  std::string description;

  detail::GPtr<ArvCamera> camera;
  detail::GPtr<ArvStream> stream;
  std::unique_ptr<Slot[]> slots;
  std::mutex slot_mutex;
  ArvBuffer* held = nullptr;  // popped and handed out; goes back to the stream on release
  bool acquiring = false;
  bool found_silent = false;  // stop() found the camera silent, and it was not started since
  bool is_gv = false;
  std::string device_ip;     // the address GVCP goes to; empty when the camera is not GigE Vision
  UdpSocket control_socket;  // the device's GVCP socket (fd -1 when not found)

  FrameSequencer sequencer;
  CameraCounters counted;  // ours; the stream's own statistics are added in counters()
  std::uint64_t closed_underruns = 0;
  std::uint64_t closed_missing_packets = 0;
  std::uint64_t closed_failures = 0;

  static void on_stream_event(void* user_data, ArvStreamCallbackType type, ArvBuffer* buffer) {
    // Runs on the Aravis stream thread: stamp and return, never block.
    if (type != ARV_STREAM_CALLBACK_TYPE_BUFFER_DONE || buffer == nullptr) return;
    auto* self = static_cast<Impl*>(user_data);
    auto* slot = static_cast<Slot*>(const_cast<void*>(arv_buffer_get_user_data(buffer)));
    if (slot == nullptr) return;
    const std::int64_t now = util::realtime_ns();
    const std::lock_guard lock(self->slot_mutex);
    slot->frame_id = arv_buffer_get_frame_id(buffer);
    slot->done_ns = now;
    slot->stamped = true;
  }

  // GevSCPD from nanoseconds with the camera's tick frequency (the conversion
  // arv_camera_gv_set_packet_delay makes), checked against the camera's range first and read
  // back after.
  void set_packet_delay(ArvCamera* cam) const {
    GError* error = nullptr;
    const std::int64_t ns = options.packet_delay_ns;
    if (arv_camera_is_feature_available(cam, "GevSCPD", &error) == FALSE) {
      g_clear_error(&error);
      throw std::runtime_error(fmt::format(
          "{}: packet_delay_ns = {}: the camera has no GevSCPD feature (remove the setting)",
          where(), ns));
    }
    const gint64 tick_hz = arv_camera_get_integer(cam, "ArvGevTimestampTickFrequency", &error);
    detail::throw_if_error(
        error, fmt::format("{}: packet_delay_ns = {}: cannot read the camera's timestamp tick "
                           "frequency, which GevSCPD counts in",
                           where(), ns));
    if (tick_hz <= 0 || tick_hz > 10'000'000'000LL) {
      throw std::runtime_error(fmt::format(
          "{}: packet_delay_ns = {}: the camera gives a timestamp tick frequency of {} Hz", where(),
          ns, tick_hz));
    }
    gint64 low = 0;
    gint64 high = 0;
    arv_camera_get_integer_bounds(cam, "GevSCPD", &low, &high, &error);
    detail::throw_if_error(error, fmt::format("{}: cannot read the range of GevSCPD", where()));
    const gint64 ticks = tick_hz * ns / 1'000'000'000LL;
    if (ticks < low || ticks > high) {
      throw std::runtime_error(fmt::format(
          "{}: packet_delay_ns = {} is GevSCPD = {} ticks of its {} Hz clock; the camera takes "
          "{}..{} ticks ({}..{} ns)",
          where(), ns, ticks, tick_hz, low, high, low * 1'000'000'000LL / tick_hz,
          high * 1'000'000'000LL / tick_hz));
    }
    arv_camera_set_integer(cam, "GevSCPD", ticks, &error);
    detail::throw_if_error(error, fmt::format("{}: cannot set packet_delay_ns = {}", where(), ns));
    const gint64 took = arv_camera_get_integer(cam, "GevSCPD", &error);
    detail::throw_if_error(error, fmt::format("{}: cannot read GevSCPD back", where()));
    if (took != ticks) {
      throw std::runtime_error(
          fmt::format("{}: asked packet_delay_ns = {} (GevSCPD = {} ticks); the camera took {}",
                      where(), ns, ticks, took));
    }
  }

  std::string where() const {
    return is_ipv4(options.camera) ? fmt::format("GigE Vision camera {}", options.camera)
                                   : fmt::format("camera '{}'", options.camera);
  }

  void open() {
    if (camera) return;
    try {
      connect();
      configure();
      make_stream();
    } catch (...) {
      close();
      throw;
    }
  }

  void connect() {
    GError* error = nullptr;
    control_socket = UdpSocket{};
    const std::vector<UdpSocket> sockets_before = udp_sockets();
    if (is_ipv4(options.camera)) {
      // Straight to the address: discovery may answer through another interface (notes).
      const std::string local = options.interface_address.empty()
                                    ? source_address_for(options.camera)
                                    : options.interface_address;
      detail::GPtr<GInetAddress> local_address(g_inet_address_new_from_string(local.c_str()));
      detail::GPtr<GInetAddress> device_address(
          g_inet_address_new_from_string(options.camera.c_str()));
      detail::GPtr<ArvDevice> device(
          arv_gv_device_new(local_address.get(), device_address.get(), &error));
      detail::throw_if_error(
          error, fmt::format("{}: no answer over GVCP from local address {} (is the camera on, "
                             "and is the address right?)",
                             where(), local));
      camera.reset(arv_camera_new_with_device(device.get(), &error));
      detail::throw_if_error(error, fmt::format("{}: cannot use the device", where()));
    } else {
      camera.reset(arv_camera_new(options.camera.c_str(), &error));
      detail::throw_if_error(error, fmt::format("{}: not found", where()));
    }
    if (!camera) throw std::runtime_error(fmt::format("{}: cannot open", where()));
    is_gv = arv_camera_is_gv_device(camera.get()) != FALSE;
    device_ip.clear();
    if (is_ipv4(options.camera)) {
      device_ip = options.camera;
    } else if (is_gv) {
      // Found by discovery: ask it at the address Aravis talks to.
      GSocketAddress* address =
          arv_gv_device_get_device_address(ARV_GV_DEVICE(arv_camera_get_device(camera.get())));
      if (G_IS_INET_SOCKET_ADDRESS(address)) {
        const std::unique_ptr<gchar, void (*)(gpointer)> text(
            g_inet_address_to_string(
                g_inet_socket_address_get_address(G_INET_SOCKET_ADDRESS(address))),
            g_free);
        if (text) device_ip = text.get();
      }
    }
    if (is_gv) find_control_socket(sockets_before);
  }

  // Remembers the device's GVCP socket: the one UDP socket that opening the camera made on the
  // local address Aravis reports (which has no port). Opening is serialized (setup_mutex), so no
  // other camera adds one meanwhile; when it is not exactly one, none is remembered.
  void find_control_socket(const std::vector<UdpSocket>& before) {
    GSocketAddress* local =
        arv_gv_device_get_interface_address(ARV_GV_DEVICE(arv_camera_get_device(camera.get())));
    sockaddr_in address{};
    if (local == nullptr ||
        g_socket_address_to_native(local, &address, sizeof(address), nullptr) == FALSE ||
        address.sin_family != AF_INET) {
      return;
    }
    int found = 0;
    for (const UdpSocket& s : udp_sockets()) {
      if (s.local.sin_addr.s_addr != address.sin_addr.s_addr) continue;
      const bool old = std::any_of(before.begin(), before.end(), [&](const UdpSocket& b) {
        return b.fd == s.fd && same_local(b.local, s.local);
      });
      if (!old && ++found == 1) control_socket = s;
    }
    if (found != 1) control_socket = UdpSocket{};
  }

  // The image asked must fit the camera's largest: WidthMax and HeightMax (SFNC: the largest
  // image at the present binning, whatever the offsets), else the sensor's size. A camera
  // without either is left to the region's read-back. Many cameras (and Aravis's fake, whose
  // Width has no range check by default) would take a larger Width and send frames that are
  // not the sensor's image.
  void check_sensor_size(ArvCamera* cam) const {
    GError* error = nullptr;
    const auto feature = [&](const char* name) -> gint64 {
      if (arv_camera_is_feature_available(cam, name, &error) == FALSE) {
        g_clear_error(&error);
        return 0;
      }
      const gint64 v = arv_camera_get_integer(cam, name, &error);
      if (error != nullptr) {
        g_clear_error(&error);
        return 0;
      }
      return v;
    };
    gint64 max_w = feature("WidthMax");
    gint64 max_h = feature("HeightMax");
    const char* what = "largest image (WidthMax x HeightMax)";
    if (max_w <= 0 || max_h <= 0) {
      max_w = feature("SensorWidth");
      max_h = feature("SensorHeight");
      what = "sensor (SensorWidth x SensorHeight)";
    }
    if (max_w <= 0 || max_h <= 0) return;
    if (options.width > max_w || options.height > max_h) {
      throw CameraRefused(fmt::format("{}: the camera's {} is {}x{}; asked for {}x{} images",
                                      where(), what, max_w, max_h, options.width, options.height));
    }
  }

  void configure() {
    ArvCamera* cam = camera.get();
    GError* error = nullptr;
    // A camera left streaming by an earlier controller refuses size changes.
    arv_camera_stop_acquisition(cam, &error);
    g_clear_error(&error);

    arv_camera_set_acquisition_mode(cam, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
    detail::throw_if_error(error,
                           fmt::format("{}: cannot set AcquisitionMode Continuous", where()));
    arv_camera_set_pixel_format(cam, detail::to_arv(options.pixel_format), &error);
    detail::throw_if_error(error, fmt::format("{}: cannot set pixel_format = {}", where(),
                                              to_string(options.pixel_format)));
    check_sensor_size(cam);
    // The region: the whole image, or the one asked grown to the camera's increments.
    const bool asked_region = options.region.width != 0;
    const char* const instead =
        asked_region ? " (a region of interest: receive whole frames instead)" : "";
    Region want{0, 0, options.width, options.height};
    if (asked_region) {
      const auto step = [&](gint (*get)(ArvCamera*, GError**)) {
        const gint v = get(cam, &error);
        g_clear_error(&error);  // a camera without the feature's increment: any value
        return std::max<gint>(v, 1);
      };
      RegionRules rules;
      rules.offset_x_step = step(arv_camera_get_x_offset_increment);
      rules.offset_y_step = step(arv_camera_get_y_offset_increment);
      rules.width_step = step(arv_camera_get_width_increment);
      rules.height_step = step(arv_camera_get_height_increment);
      want = align_region(options.region, rules, options.width, options.height);
    }
    arv_camera_set_region(cam, want.x, want.y, want.width, want.height, &error);
    detail::throw_if_error(
        error, fmt::format("{}: cannot set the region x {} y {} width {} height {}{}", where(),
                           want.x, want.y, want.width, want.height, instead));
    arv_camera_set_frame_rate(cam, options.frame_rate_hz, &error);
    detail::throw_if_error(
        error, fmt::format("{}: cannot set frame_rate_hz = {}", where(), options.frame_rate_hz));

    // Read everything back: a camera may round or refuse silently.
    gint x = 0;
    gint y = 0;
    gint width = 0;
    gint height = 0;
    arv_camera_get_region(cam, &x, &y, &width, &height, &error);
    detail::throw_if_error(error, fmt::format("{}: cannot read the region", where()));
    if (x != want.x || y != want.y || width != want.width || height != want.height) {
      throw CameraRefused(fmt::format(
          "{}: asked the region x {} y {} width {} height {} of the {}x{} image; the camera "
          "took x {} y {} width {} height {}{}",
          where(), want.x, want.y, want.width, want.height, options.width, options.height, x, y,
          width, height, instead));
    }
    format = {want.width, want.height, options.pixel_format};
    origin_x = want.x;
    origin_y = want.y;
    const ArvPixelFormat pixel_format = arv_camera_get_pixel_format(cam, &error);
    detail::throw_if_error(error, fmt::format("{}: cannot read the pixel format", where()));
    if (pixel_format != detail::to_arv(options.pixel_format)) {
      throw CameraRefused(fmt::format("{}: asked pixel_format = {}; the camera took 0x{:08x}",
                                      where(), to_string(options.pixel_format),
                                      static_cast<unsigned>(pixel_format)));
    }
    const double rate = arv_camera_get_frame_rate(cam, &error);
    detail::throw_if_error(error, fmt::format("{}: cannot read the frame rate", where()));
    if (std::abs(rate - options.frame_rate_hz) > 0.01 * options.frame_rate_hz) {
      double low = 0.0;
      double high = 0.0;
      arv_camera_get_frame_rate_bounds(cam, &low, &high, &error);
      g_clear_error(&error);
      throw std::runtime_error(
          fmt::format("{}: asked frame_rate_hz = {}; the camera runs at {} (its range: {}..{})",
                      where(), options.frame_rate_hz, rate, low, high));
    }

    if (is_gv) {
      // A packet socket (used when Aravis runs as root) adds latency and, with packets above
      // the MTU, delivered short frames marked complete (notes): plain UDP only.
      arv_camera_gv_set_stream_options(cam, ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
      // The packet size is ours to choose (at most the link MTU), not probed and changed by
      // Aravis when the stream is made.
      arv_camera_gv_set_packet_size_adjustment(cam, ARV_GV_PACKET_SIZE_ADJUSTMENT_NEVER);
      arv_camera_gv_set_packet_size(cam, options.packet_size_bytes, &error);
      detail::throw_if_error(error, fmt::format("{}: cannot set packet_size_bytes = {}", where(),
                                                options.packet_size_bytes));
      const guint packet_size = arv_camera_gv_get_packet_size(cam, &error);
      detail::throw_if_error(error, fmt::format("{}: cannot read the packet size", where()));
      if (packet_size > static_cast<guint>(options.packet_size_bytes) || packet_size < 576) {
        throw std::runtime_error(fmt::format("{}: asked packet_size_bytes = {}; the camera took {}",
                                             where(), options.packet_size_bytes, packet_size));
      }
      if (options.packet_delay_ns >= 0) set_packet_delay(cam);
    }

    const guint payload = arv_camera_get_payload(cam, &error);
    detail::throw_if_error(error, fmt::format("{}: cannot read the payload size", where()));
    if (payload != format.payload_bytes()) {
      throw std::runtime_error(fmt::format(
          "{}: the camera sends {} bytes per frame, {} needs {} (chunk data or padding on?)",
          where(), payload, to_string(format), format.payload_bytes()));
    }
  }

  void make_stream() {
    GError* error = nullptr;
    stream.reset(arv_camera_create_stream(camera.get(), &Impl::on_stream_event, this, &error));
    detail::throw_if_error(error, fmt::format("{}: cannot create the stream", where()));
    if (!stream) throw std::runtime_error(fmt::format("{}: cannot create the stream", where()));

    if (is_gv) {
      // The default socket buffer drops packets at 640x480 and 100 fps (notes). Aravis applies
      // the FIXED size when the first frame starts, so the socket is sized here as well, before
      // any packet arrives (without that the first frame often came incomplete).
      g_object_set(stream.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
                   "socket-buffer-size", static_cast<gint>(options.socket_buffer_bytes),
                   "packet-resend",
                   options.packet_resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS
                                         : ARV_GV_STREAM_PACKET_RESEND_NEVER,
                   "packet-timeout", to_microseconds(options.packet_timeout), "frame-retention",
                   to_microseconds(options.frame_retention), nullptr);
      if (!size_stream_socket(arv_gv_stream_get_port(ARV_GV_STREAM(stream.get())),
                              options.socket_buffer_bytes)) {
        util::log_warn(
            "{}: could not size the stream socket before the first frame; it may "
            "come incomplete",
            where());
      }
      const std::int64_t rmem_max = read_rmem_max();
      if (rmem_max >= 0 && static_cast<std::size_t>(rmem_max) < options.socket_buffer_bytes) {
        util::log_warn(
            "{}: socket_buffer_bytes = {} but net.core.rmem_max = {}: the kernel caps the "
            "buffer (raise it with sysctl -w net.core.rmem_max={})",
            where(), options.socket_buffer_bytes, rmem_max, options.socket_buffer_bytes);
      }
    }

    const std::size_t count = static_cast<std::size_t>(options.buffer_count);
    slots = std::make_unique<Slot[]>(count);
    for (std::size_t i = 0; i < count; ++i) {
      ArvBuffer* buffer = arv_buffer_new_full(format.payload_bytes(), nullptr, &slots[i], nullptr);
      if (buffer == nullptr) {
        throw std::runtime_error(fmt::format("{}: cannot allocate frame buffers", where()));
      }
      arv_stream_push_buffer(stream.get(), buffer);  // the stream owns it from here
    }

    const char* serial = arv_camera_get_device_serial_number(camera.get(), &error);
    g_clear_error(&error);
    description = fmt::format(
        "{} (serial {}): {}{} at {} fps, {} buffers{}", where(), serial != nullptr ? serial : "?",
        to_string(format),
        format.width == options.width && format.height == options.height
            ? std::string()
            : fmt::format(" region of interest at ({}, {}) of {}x{}", origin_x, origin_y,
                          options.width, options.height),
        options.frame_rate_hz, options.buffer_count,
        is_gv ? fmt::format(", packets {} B{}, socket buffer {} B, resend {}",
                            options.packet_size_bytes,
                            options.packet_delay_ns >= 0
                                ? fmt::format(" {} ns apart", options.packet_delay_ns)
                                : std::string(),
                            options.socket_buffer_bytes, options.packet_resend ? "on" : "off")
              : std::string());
  }

  void push_back(ArvBuffer* buffer) noexcept {
    if (buffer == nullptr || !stream) return;
    // A frame whose leader packet is lost would otherwise come back with the id and timestamp
    // of this buffer's previous use.
    arv_buffer_set_frame_id(buffer, 0);
    arv_buffer_set_timestamp(buffer, 0);
    arv_stream_push_buffer(stream.get(), buffer);
  }

  void release() noexcept {
    push_back(held);
    held = nullptr;
  }

  void drain() noexcept {
    if (!stream) return;
    while (ArvBuffer* buffer = arv_stream_try_pop_buffer(stream.get()))
      push_back(buffer);
  }

  void start() {
    open();
    if (acquiring) return;
    release();
    drain();
    sequencer.restart();
    GError* error = nullptr;
    arv_camera_start_acquisition(camera.get(), &error);
    detail::throw_if_error(error, fmt::format("{}: cannot start acquisition", where()));
    acquiring = true;
    found_silent = false;
  }

  // Whether the camera answers a GVCP read now (a short probe); true when there is nothing to
  // ask (not GigE Vision, or not open).
  bool answers() const noexcept {
    return !camera || device_ip.empty() ||
           gvcp_device_answers(device_ip, std::chrono::milliseconds(300));
  }

  void stop() noexcept {
    if (acquiring) found_silent = !answers();
    stop_acquisition(!found_silent);
  }

  // `camera_answers`: the probe's result. Telling a camera that is gone to stop costs Aravis's
  // 2.5 s control timeout.
  void stop_acquisition(bool camera_answers) noexcept {
    release();
    if (!acquiring) return;
    acquiring = false;
    if (camera_answers) {
      GError* error = nullptr;
      arv_camera_stop_acquisition(camera.get(), &error);
      if (error != nullptr) last_error = detail::take_error(error, where() + ": stop acquisition");
    }
    drain();
  }

  // For a camera that no longer answers: makes every further GVCP command of its device fail at
  // once instead of waiting for it. Aravis 0.8.26 has no setting for its GVCP timeout (500 ms)
  // or tries (5), and dropping the objects sends three commands, each waited for in full
  // (7.5 s per camera, measured): the stream's "stop stream channel" (SCP host port 0), the
  // heartbeat's control-channel read, which the device's finalize joins, and its "leave
  // control". shutdown(SHUT_WR) on the device's control socket (found by the local address
  // Aravis reports) makes each send fail with EPIPE; Aravis gives up after its tries without
  // waiting. Linux applies it to an unconnected UDP socket although it returns ENOTCONN. At
  // most the heartbeat's read already under way is waited for (500 ms). The socket is closed
  // with the device as before; nothing else changes.
  void stop_talking_to_device() noexcept {
    sockaddr_in now{};
    socklen_t length = sizeof(now);
    // Still the socket found at open (the device keeps it open until it is finalized).
    if (control_socket.fd < 0 ||
        ::getsockname(control_socket.fd, reinterpret_cast<sockaddr*>(&now), &length) != 0 ||
        now.sin_family != AF_INET || !same_local(now, control_socket.local) ||
        (::shutdown(control_socket.fd, SHUT_WR) != 0 && errno != ENOTCONN)) {
      util::log_warn(
          "{}: does not answer, and its control socket was not found: closing waits "
          "for Aravis's timeouts (several seconds)",
          where());
    }
  }

  void close() noexcept {
    // Not asked again when stop() just found it silent (sensor_node stops, then destroys).
    const bool camera_answers = !found_silent && answers();
    found_silent = false;
    stop_acquisition(camera_answers);
    if (stream) {
      guint64 completed = 0;
      guint64 failures = 0;
      guint64 underruns = 0;
      arv_stream_get_statistics(stream.get(), &completed, &failures, &underruns);
      closed_underruns += underruns;
      closed_failures += failures;
      closed_missing_packets +=
          arv_stream_get_info_uint64_by_name(stream.get(), "n_missing_packets");
    }
    if (!camera_answers && is_gv) stop_talking_to_device();
    // Never from the stream's own callback: dropping its last reference joins its thread.
    stream.reset();
    slots.reset();
    camera.reset();
  }

  Frame wait(Duration timeout) noexcept {
    release();
    Frame frame;
    if (!stream || !acquiring) {
      frame.status = FrameStatus::kCameraError;
      return frame;
    }
    // Drain first: a buffer may reach the output queue without a BUFFER_DONE callback.
    ArvBuffer* buffer = arv_stream_try_pop_buffer(stream.get());
    if (buffer == nullptr && timeout.count() > 0) {
      const auto us = static_cast<guint64>((timeout.count() + 999) / 1000);
      buffer = arv_stream_timeout_pop_buffer(stream.get(), us);
    }
    if (buffer == nullptr) {
      ++counted.wait_timeouts;
      return frame;
    }
    held = buffer;
    const std::int64_t popped_ns = util::realtime_ns();
    const std::uint64_t frame_id = arv_buffer_get_frame_id(buffer);

    frame.received = true;
    frame.camera_frame_id = frame_id;
    frame.camera_timestamp_ns = static_cast<std::int64_t>(arv_buffer_get_timestamp(buffer));
    frame.receive_timestamp_ns = popped_ns;
    if (auto* slot = static_cast<Slot*>(const_cast<void*>(arv_buffer_get_user_data(buffer)))) {
      const std::lock_guard lock(slot_mutex);
      // Aravis 0.8.26 queues the buffer before it calls back (and at times does not call back),
      // so the stamp may not be there yet: the pop time, microseconds later, stands in.
      if (slot->stamped && slot->frame_id == frame_id) {
        frame.receive_timestamp_ns = std::min(slot->done_ns, popped_ns);
      }
      slot->stamped = false;
    }

    frame.status = check(buffer, frame);
    if (frame_id == 0) {
      // The frame's leader never arrived, so its block id is unknown (GigE Vision never uses
      // 0): it cannot be placed in the stream, is never whole, and leaves the sequence alone;
      // the next frame with an id counts it among those lost.
      if (frame.status == FrameStatus::kComplete) frame.status = FrameStatus::kMissingPackets;
      frame.image = ImageView{};
      frame.sequence = 0;
      frame.frames_lost = 0;
    } else {
      const FrameSequencer::Step step = sequencer.next(frame_id);
      frame.sequence = step.sequence;
      frame.frames_lost = step.frames_lost;
      frame.first_after_start = step.first_after_start;
      counted.frames_lost += step.frames_lost;
      // A reordered frame (an incomplete one closed after a newer one) was counted lost when
      // the newer one came: it did arrive after all.
      if (step.late && !step.repeated && counted.frames_lost > 0) --counted.frames_lost;
    }
    ++counted.frames;
    if (frame.status == FrameStatus::kComplete) {
      ++counted.completed;
    } else {
      ++counted.incomplete;
    }
    return frame;
  }

  // The status of a popped buffer; sets frame.image only for a whole frame of our format.
  FrameStatus check(ArvBuffer* buffer, Frame& frame) const noexcept {
    const FrameStatus status = map_buffer_status(arv_buffer_get_status(buffer));
    if (status != FrameStatus::kComplete) return status;
    if (arv_buffer_get_payload_type(buffer) != ARV_BUFFER_PAYLOAD_TYPE_IMAGE) {
      return FrameStatus::kWrongFormat;
    }
    gint x_padding = 0;
    gint y_padding = 0;
    arv_buffer_get_image_padding(buffer, &x_padding, &y_padding);
    if (arv_buffer_get_image_width(buffer) != format.width ||
        arv_buffer_get_image_height(buffer) != format.height ||
        arv_buffer_get_image_pixel_format(buffer) != detail::to_arv(format.pixel_format) ||
        x_padding != 0 || y_padding != 0) {
      return FrameStatus::kWrongFormat;
    }
    // Every frame's size is checked: a frame marked complete has held a fifth of its bytes.
    std::size_t size = 0;
    const void* data = arv_buffer_get_data(buffer, &size);
    if (data == nullptr || size != format.payload_bytes()) return FrameStatus::kSizeMismatch;
    frame.image =
        ImageView{static_cast<const std::uint8_t*>(data),
                  format.width,
                  format.height,
                  static_cast<std::size_t>(format.width) * bytes_per_pixel(format.pixel_format),
                  format.pixel_format,
                  origin_x,
                  origin_y};
    return FrameStatus::kComplete;
  }

  CameraCounters counters() const noexcept {
    CameraCounters c = counted;
    c.underruns = closed_underruns;
    c.failures = closed_failures;
    c.missing_packets = closed_missing_packets;
    if (stream) {
      guint64 completed = 0;
      guint64 failures = 0;
      guint64 underruns = 0;
      arv_stream_get_statistics(stream.get(), &completed, &failures, &underruns);
      c.underruns += underruns;
      c.failures += failures;
      c.missing_packets += arv_stream_get_info_uint64_by_name(stream.get(), "n_missing_packets");
    }
    return c;
  }
};

AravisCamera::AravisCamera(AravisCameraOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

// Aravis is not safe for opening, configuring and closing several cameras on several threads
// at once (upstream issue 159: GLib errors, a camera that never delivers): those steps take
// one process-wide lock. Frames still flow in parallel.
static std::mutex& setup_mutex() {
  static std::mutex m;
  return m;
}

AravisCamera::~AravisCamera() {
  std::lock_guard lock(setup_mutex());
  impl_.reset();
}

void AravisCamera::open() {
  std::lock_guard lock(setup_mutex());
  impl_->open();
}

void AravisCamera::start() {
  std::lock_guard lock(setup_mutex());
  impl_->start();
}

void AravisCamera::stop() noexcept {
  std::lock_guard lock(setup_mutex());
  impl_->stop();
}

bool AravisCamera::reopen() noexcept {
  std::lock_guard lock(setup_mutex());
  if (is_ipv4(impl_->options.camera) &&
      !gvcp_device_answers(impl_->options.camera, std::chrono::milliseconds(300))) {
    impl_->last_error = impl_->where() + ": no answer over GVCP (camera off or unreachable)";
    return false;
  }
  impl_->close();
  try {
    impl_->open();
    impl_->start();
  } catch (const std::exception& e) {
    impl_->last_error = e.what();
    impl_->close();
    return false;
  } catch (...) {
    impl_->last_error = impl_->where() + ": unknown error while reopening";
    impl_->close();
    return false;
  }
  ++impl_->counted.reopens;
  return true;
}

const std::string& AravisCamera::last_error() const noexcept {
  return impl_->last_error;
}

Frame AravisCamera::wait_frame(Duration timeout) noexcept {
  return impl_->wait(timeout);
}

void AravisCamera::release_frame() noexcept {
  impl_->release();
}

CameraCounters AravisCamera::counters() const noexcept {
  return impl_->counters();
}

const FrameFormat& AravisCamera::format() const noexcept {
  return impl_->format;
}

Duration AravisCamera::nominal_period() const noexcept {
  return Duration(impl_->nominal_period_ns);
}

std::string AravisCamera::describe() const {
  return impl_->description.empty() ? impl_->where() + " (not open)" : impl_->description;
}

const AravisCameraOptions& AravisCamera::options() const noexcept {
  return impl_->options;
}

}  // namespace tactile::camera
