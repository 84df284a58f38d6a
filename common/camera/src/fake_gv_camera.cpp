#include "tactile/camera/fake_gv_camera.hpp"

#include <arpa/inet.h>
#include <dlfcn.h>
#include <fmt/core.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "aravis_support.hpp"
#include "tactile/camera/private_network.hpp"
#include "tactile/util/clock.hpp"

namespace tactile::camera {
namespace {
// The frame period (us) of the fake camera whose thread this is; 0 on every other thread.
thread_local std::int64_t t_fake_camera_period_us = 0;
// The inter-packet delay (ns) a receiver set on that camera (GevSCPD), and when its thread
// last sent a packet (CLOCK_MONOTONIC); 0 on every other thread.
thread_local std::int64_t t_fake_camera_packet_delay_ns = 0;
thread_local std::int64_t t_fake_camera_last_send_ns = 0;  // 0: no packet yet in this frame
// The time between the current frame's packets so far: from the end of each send to the start of
// the next, summed (SentFrame::previous_frame_packet_gaps_ns).
thread_local std::int64_t t_fake_camera_frame_gaps_ns = 0;
// GigE Vision bootstrap registers: the stream channel's packet delay (SCPD0) and the timestamp
// tick frequency it counts in.
constexpr guint32 kGevScpd0 = 0x0d08;
constexpr guint32 kGevTickFrequencyHigh = 0x093c;
constexpr guint32 kGevTickFrequencyLow = 0x0940;
// The last microseconds before a frame, still spun through: a thread woken from a sleep runs tens
// of microseconds late on a busy machine, and the frame would leave that much after its time.
constexpr std::int64_t kFakeCameraSpinUs = 100;
}  // namespace
}  // namespace tactile::camera

// Aravis 0.8.26's ArvGvFakeCamera thread waits for its next frame, the next multiple of the
// frame period in g_get_real_time () microseconds, by polling its control sockets with the
// timeout (guint64 next_timestamp_us - g_get_real_time ()) / 1000, clamped to 0..100 ms, until
// that time. Two consequences, both mended here:
// - Through the last millisecond before each frame the timeout is 0: the thread spins on
//   poll(2), half a millisecond per frame on average (a sixth of a core for the rig's two
//   cameras at 200 fps, taken from the programs it serves).
// - When the frame time passes between its loop test and that line, the unsigned difference
//   wraps and the camera waits 100 ms before the frame; about one frame in a hundred on a busy
//   machine (upstream pull request 1089).
// This program's g_poll is found before GLib's (the dynamic linker looks in the executable
// first) and is GLib's own on Linux, poll(2), with two changes on a fake camera's thread while
// it streams: a wait longer than its frame period can only be that wrap, and is not waited; and
// a wait of 0 in the last millisecond before a frame boundary sleeps until kFakeCameraSpinUs
// before it (ppoll(2), microseconds, still woken by a control packet; the thread's timer slack
// set to 1 ns), and spins only through those. A poll of 0 just after a boundary (the frame is
// due) returns at once, as before. Periods under 2 ms keep the spin: there the two cases cannot
// be told apart by the time alone.
static_assert(sizeof(GPollFD) == sizeof(pollfd) &&
                  offsetof(GPollFD, revents) == offsetof(pollfd, revents),
              "g_poll passes GPollFD to poll(2) as GLib does on Linux");
extern "C" gint g_poll(GPollFD* fds, guint nfds, gint timeout) {
  const std::int64_t period_us = tactile::camera::t_fake_camera_period_us;
  auto* pfds = reinterpret_cast<pollfd*>(fds);
  if (period_us > 0) {
    if (timeout > period_us / 1000) timeout = 0;
    if (timeout == 0 && period_us >= 2000) {
      const std::int64_t left_us = period_us - g_get_real_time() % period_us;
      if (left_us < 1000 && left_us > tactile::camera::kFakeCameraSpinUs) {
        const timespec wait{
            0, static_cast<long>((left_us - tactile::camera::kFakeCameraSpinUs) * 1000)};
        return ::ppoll(pfds, nfds, &wait, nullptr);
      }
    }
  }
  return ::poll(pfds, nfds, timeout);
}

// Aravis 0.8.26's ArvGvFakeCamera sends every packet of a frame back to back and ignores the
// stream channel's packet delay (GevSCPD), which a lab sets when cameras share a link. Its
// thread sends them with g_socket_send_to, on which this program's definition is found first,
// as for g_poll: on a fake camera's thread with a delay set, a send waits (spinning: the delays
// are microseconds) until that delay has passed since the end of the frame's previous send, then
// sends through GLib's own; the time between a frame's sends is summed for SentFrame. Every
// other thread sends at once.
extern "C" gssize g_socket_send_to(GSocket* socket, GSocketAddress* address, const gchar* buffer,
                                   gsize size, GCancellable* cancellable, GError** error) {
  using SendTo =
      gssize (*)(GSocket*, GSocketAddress*, const gchar*, gsize, GCancellable*, GError**);
  static const auto glib_send_to = reinterpret_cast<SendTo>(::dlsym(RTLD_NEXT, "g_socket_send_to"));
  if (tactile::camera::t_fake_camera_period_us == 0)
    return glib_send_to(socket, address, buffer, size, cancellable, error);
  const std::int64_t delay_ns = tactile::camera::t_fake_camera_packet_delay_ns;
  const std::int64_t last = tactile::camera::t_fake_camera_last_send_ns;
  std::int64_t start = tactile::util::monotonic_ns();
  if (delay_ns > 0 && last != 0) {
    while (start < last + delay_ns)
      start = tactile::util::monotonic_ns();
  }
  if (last != 0) tactile::camera::t_fake_camera_frame_gaps_ns += start - last;
  const gssize sent = glib_send_to(socket, address, buffer, size, cancellable, error);
  tactile::camera::t_fake_camera_last_send_ns = tactile::util::monotonic_ns();
  return sent;
}

namespace tactile::camera {

// GigE Vision sends Mono16 little-endian; ImageView holds host-endian pixels, and the frame is
// passed through with one memcpy.
static_assert(std::endian::native == std::endian::little,
              "FakeGvCamera copies Mono16 pixels as they are: a little-endian host is assumed");

namespace {

bool gvcp_port_taken(const std::string& address) {
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(3956);
  if (inet_pton(AF_INET, address.c_str(), &local.sin_addr) != 1) return false;
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  const bool taken = ::bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof(local)) != 0 &&
                     errno == EADDRINUSE;
  ::close(fd);
  return taken;
}

}  // namespace

void FakeGvCameraOptions::validate() const {
  auto bad = [](std::string_view option, const auto& value, std::string_view rule) {
    return std::invalid_argument(
        fmt::format("fake camera option {} = {}: {}", option, value, rule));
  };
  in_addr parsed{};
  if (inet_pton(AF_INET, address.c_str(), &parsed) != 1) {
    throw bad("address", address, "must be an IPv4 address such as 127.0.0.2");
  }
  if (serial.empty() || serial.size() > 15)
    throw bad("serial", serial, "must have 1 to 15 characters");
  if (width < 1 || width > 2048) throw bad("width", width, "must be in 1..2048");
  if (height < 1 || height > 2048) throw bad("height", height, "must be in 1..2048");
  if (!(frame_rate_hz >= 0.1 && frame_rate_hz <= 1000.0)) {
    throw bad("frame_rate_hz", frame_rate_hz, "must be in 0.1..1000");
  }
  if (!(gvsp_lost_ratio >= 0.0 && gvsp_lost_ratio <= 1.0)) {
    throw bad("gvsp_lost_ratio", gvsp_lost_ratio, "must be in 0..1");
  }
}

struct FakeGvCamera::Impl {
  explicit Impl(FakeGvCameraOptions o) : options(std::move(o)) {
    options.validate();
    format = {options.width, options.height, options.pixel_format};
    for (auto& image : images)
      image.resize(format.payload_bytes());
  }

  ~Impl() {
    // Joins the camera thread first: nothing below is touched afterwards.
    camera.reset();
  }

  // Declared first: destroyed last, after the fake camera.
  detail::AravisUse aravis;
  FakeGvCameraOptions options;
  FrameFormat format;

  // The double buffer. The renderer writes the back image without a lock, then swaps under
  // front_mutex; the camera thread copies the front image under front_mutex. A swap therefore
  // waits for a copy in progress, and the image a renderer writes is never being read.
  std::mutex publish_mutex;
  std::mutex front_mutex;
  std::array<std::vector<std::uint8_t>, 2> images;
  std::array<std::uint64_t, 2> frame_ids{};
  std::array<std::int64_t, 2> timestamps{};
  int front = -1;       // -1: nothing published yet
  SentFrame last_sent;  // guarded by front_mutex

  std::mutex observer_mutex;
  SentObserver observer;
  std::atomic<std::uint64_t> frames_sent{0};
  std::atomic<double> lost_ratio{0.0};

  detail::GPtr<ArvGvFakeCamera> camera;  // declared last: destroyed first

  static void fill(ArvBuffer* buffer, void* user_data, guint32 /*exposure_time_us*/,
                   guint32 /*gain*/, ArvPixelFormat pixel_format) {
    // Runs once per frame on the fake camera's only thread, which also answers GVCP: one copy.
    auto* self = static_cast<Impl*>(user_data);
    // The registers a receiver writes, read per frame; not owned.
    ArvFakeCamera* fake =
        self->camera ? arv_gv_fake_camera_get_fake_camera(self->camera.get()) : nullptr;
    // This thread streams at the camera's period (see g_poll above). The register, not the
    // options: a client may change the frame rate.
    guint32 period_us = 0;
    if (fake && arv_fake_camera_read_register(
                    fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US, &period_us)) {
      if (t_fake_camera_period_us == 0) prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
      t_fake_camera_period_us = period_us;
    }
    // The packet delay a receiver set (GevSCPD, in ticks of the camera's clock): the frame's
    // packets, sent after this callback, are spaced by it (g_socket_send_to above).
    guint32 scpd_ticks = 0;
    guint32 tick_high = 0;
    guint32 tick_low = 0;
    if (fake && arv_fake_camera_read_register(fake, kGevScpd0, &scpd_ticks) &&
        arv_fake_camera_read_register(fake, kGevTickFrequencyHigh, &tick_high) &&
        arv_fake_camera_read_register(fake, kGevTickFrequencyLow, &tick_low)) {
      const auto tick_hz = (static_cast<std::uint64_t>(tick_high) << 32) | tick_low;
      t_fake_camera_packet_delay_ns =
          tick_hz > 0 ? static_cast<std::int64_t>(scpd_ticks * 1'000'000'000ULL / tick_hz) : 0;
    }
    SentFrame sent;
    sent.packet_delay_ns = t_fake_camera_packet_delay_ns;
    // The previous frame's packets have all left: this frame's first packet waits for no delay.
    sent.previous_frame_packet_gaps_ns = t_fake_camera_frame_gaps_ns;
    t_fake_camera_frame_gaps_ns = 0;
    t_fake_camera_last_send_ns = 0;
    sent.block_id = arv_buffer_get_frame_id(buffer);
    sent.fill_time_ns = util::realtime_ns();
    const int width = arv_buffer_get_image_width(buffer);
    const int height = arv_buffer_get_image_height(buffer);
    // The region of interest a receiver set (GenICam OffsetX/OffsetY with Width/Height): the
    // frame holds that part of the published sensor image.
    guint32 offset_x = 0;
    guint32 offset_y = 0;
    if (fake) {
      arv_fake_camera_read_register(fake, ARV_FAKE_CAMERA_REGISTER_X_OFFSET, &offset_x);
      arv_fake_camera_read_register(fake, ARV_FAKE_CAMERA_REGISTER_Y_OFFSET, &offset_y);
    }
    sent.origin_x = static_cast<int>(offset_x);
    sent.origin_y = static_cast<int>(offset_y);
    sent.width = width;
    sent.height = height;
    // Size from the geometry: arv_buffer_get_data reports 0 here (Aravis issue 955).
    const std::size_t bytes = detail::frame_bytes(width, height, pixel_format);
    const std::size_t pixel_bytes = bytes_per_pixel(self->format.pixel_format);
    void* data = const_cast<void*>(arv_buffer_get_data(buffer, nullptr));
    sent.format_matched =
        width >= 1 && height >= 1 && offset_x <= 65535 && offset_y <= 65535 &&
        sent.origin_x + width <= self->format.width &&
        sent.origin_y + height <= self->format.height &&
        pixel_format == detail::to_arv(self->format.pixel_format) &&
        bytes == static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * pixel_bytes;
    {
      const std::lock_guard lock(self->front_mutex);
      if (self->front >= 0 && sent.format_matched && data != nullptr) {
        const auto f = static_cast<std::size_t>(self->front);
        const std::size_t sensor_row = static_cast<std::size_t>(self->format.width) * pixel_bytes;
        const std::size_t row = static_cast<std::size_t>(width) * pixel_bytes;
        const std::uint8_t* from =
            self->images[f].data() + offset_y * sensor_row + offset_x * pixel_bytes;
        auto* to = static_cast<std::uint8_t*>(data);
        if (row == sensor_row) {
          std::memcpy(to, from, bytes);
        } else {
          for (int y = 0; y < height; ++y)
            std::memcpy(to + static_cast<std::size_t>(y) * row,
                        from + static_cast<std::size_t>(y) * sensor_row, row);
        }
        sent.frame_id = self->frame_ids[f];
        sent.timestamp_ns = self->timestamps[f];
      }
      self->last_sent = sent;
    }
    // The receiver's camera timestamp: the renderer's, so ground truth matches exactly.
    arv_buffer_set_timestamp(buffer, static_cast<guint64>(sent.timestamp_ns));
    self->frames_sent.fetch_add(1, std::memory_order_relaxed);
    const std::lock_guard lock(self->observer_mutex);
    if (self->observer) {
      // Nothing may unwind through Aravis's C frames.
      try {
        self->observer(sent);
      } catch (...) {  // the frame is sent all the same
      }
    }
  }

  [[noreturn]] void throw_port_taken() const {
    throw std::runtime_error(fmt::format(
        "fake GigE Vision camera {}: cannot serve on {}: GVCP port 3956 on that address is "
        "already taken (another fake camera, arv-fake-gv-camera-0.8?)",
        options.serial, options.address));
  }

  void start() {
    // GLib binds UDP sockets with SO_REUSEADDR, so a second fake camera on the same address
    // would start and steal the first one's packets: probe the port without it first.
    if (gvcp_port_taken(options.address)) throw_port_taken();
    camera.reset(arv_gv_fake_camera_new(options.address.c_str(), options.serial.c_str()));
    if (!camera || arv_gv_fake_camera_is_running(camera.get()) == FALSE) {
      camera.reset();
      if (!ipv4_address_assigned(options.address)) {
        throw std::runtime_error(fmt::format(
            "fake GigE Vision camera {}: address {} is not assigned to any interface. Add it "
            "(root): `ip addr add {}/8 dev lo` (remove it later with `ip addr del {}/8 dev lo`), "
            "or run inside a private network namespace: `unshare -rn sh -c 'ip link set lo up; "
            "ip addr add {}/8 dev lo; exec PROGRAM'` (tactile::camera::enter_private_network "
            "does the same in-process)",
            options.serial, options.address, options.address, options.address, options.address));
      }
      throw_port_taken();
    }
    ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(camera.get());  // not owned
    // The sensor is the published image; a receiver may set a region of interest inside it.
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_WIDTH,
                                   static_cast<guint32>(options.width));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_HEIGHT,
                                   static_cast<guint32>(options.height));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_X_OFFSET, 0);
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_Y_OFFSET, 0);
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH,
                                   static_cast<guint32>(options.width));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT,
                                   static_cast<guint32>(options.height));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT,
                                   static_cast<guint32>(detail::to_arv(options.pixel_format)));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                   static_cast<guint32>(std::llround(1e6 / options.frame_rate_hz)));
    set_lost_ratio(options.gvsp_lost_ratio);
    detail::set_fill_pattern(fake, &Impl::fill, this);
  }

  void set_lost_ratio(double ratio) {
    if (!(ratio >= 0.0 && ratio <= 1.0)) {
      throw std::invalid_argument(
          fmt::format("fake camera option gvsp_lost_ratio = {}: must be in 0..1", ratio));
    }
    g_object_set(camera.get(), "gvsp-lost-ratio", ratio, nullptr);
    lost_ratio.store(ratio);
  }

  bool publish(const ImageView& image, std::uint64_t frame_id, std::int64_t timestamp_ns) noexcept {
    if (image.data == nullptr || image.width != format.width || image.height != format.height ||
        image.format != format.pixel_format) {
      return false;
    }
    const std::size_t row_bytes =
        static_cast<std::size_t>(format.width) * bytes_per_pixel(format.pixel_format);
    if (image.stride_bytes < row_bytes) return false;

    const std::lock_guard publishing(publish_mutex);
    // Only publishers change `front`, and they hold publish_mutex: reading it here is safe.
    const std::size_t back = front == 0 ? 1 : 0;
    std::uint8_t* out = images[back].data();
    if (image.stride_bytes == row_bytes) {
      std::memcpy(out, image.data, format.payload_bytes());
    } else {
      for (int y = 0; y < format.height; ++y) {
        std::memcpy(out + static_cast<std::size_t>(y) * row_bytes,
                    image.data + static_cast<std::size_t>(y) * image.stride_bytes, row_bytes);
      }
    }
    frame_ids[back] = frame_id;
    timestamps[back] = timestamp_ns;
    const std::lock_guard swapping(front_mutex);
    front = static_cast<int>(back);
    return true;
  }
};

FakeGvCamera::FakeGvCamera(FakeGvCameraOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {
  impl_->start();
}

FakeGvCamera::~FakeGvCamera() = default;

bool FakeGvCamera::is_running() const noexcept {
  return impl_->camera && arv_gv_fake_camera_is_running(impl_->camera.get()) != FALSE;
}

const FakeGvCameraOptions& FakeGvCamera::options() const noexcept {
  return impl_->options;
}

FrameFormat FakeGvCamera::format() const noexcept {
  return impl_->format;
}

bool FakeGvCamera::publish(const ImageView& image, std::uint64_t frame_id,
                           std::int64_t timestamp_ns) noexcept {
  return impl_->publish(image, frame_id, timestamp_ns);
}

void FakeGvCamera::set_gvsp_lost_ratio(double ratio) {
  impl_->set_lost_ratio(ratio);
}

double FakeGvCamera::gvsp_lost_ratio() const noexcept {
  return impl_->lost_ratio.load();
}

void FakeGvCamera::set_sent_observer(SentObserver observer) {
  const std::lock_guard lock(impl_->observer_mutex);
  impl_->observer = std::move(observer);
}

SentFrame FakeGvCamera::last_sent() const noexcept {
  const std::lock_guard lock(impl_->front_mutex);
  return impl_->last_sent;
}

std::uint64_t FakeGvCamera::frames_sent() const noexcept {
  return impl_->frames_sent.load(std::memory_order_relaxed);
}

}  // namespace tactile::camera
