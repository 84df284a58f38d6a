#include "aravis_support.hpp"

#include <mutex>
#include <stdexcept>
#include <string>

namespace tactile::camera::detail {

std::string take_error(GError* error, std::string_view what) {
  if (error == nullptr) return {};
  std::string message(what);
  message += ": ";
  message += error->message != nullptr ? error->message : "unknown error";
  g_error_free(error);
  return message;
}

void throw_if_error(GError* error, std::string_view what) {
  if (error != nullptr) throw std::runtime_error(take_error(error, what));
}

namespace {
std::mutex& use_mutex() {
  static std::mutex m;
  return m;
}
int use_count = 0;
}  // namespace

AravisUse::AravisUse() {
  const std::lock_guard lock(use_mutex());
  ++use_count;
}

AravisUse::~AravisUse() {
  const std::lock_guard lock(use_mutex());
  if (--use_count == 0) arv_shutdown();
}

ArvPixelFormat to_arv(PixelFormat format) {
  return format == PixelFormat::kMono8 ? ARV_PIXEL_FORMAT_MONO_8 : ARV_PIXEL_FORMAT_MONO_16;
}

std::size_t frame_bytes(int width, int height, ArvPixelFormat format) {
  if (width <= 0 || height <= 0) return 0;
  std::size_t bytes_per_pixel = 0;
  switch (format) {
    case ARV_PIXEL_FORMAT_MONO_8:
      bytes_per_pixel = 1;
      break;
    case ARV_PIXEL_FORMAT_MONO_16:
      bytes_per_pixel = 2;
      break;
    default:
      return 0;
  }
  return static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * bytes_per_pixel;
}

void set_fill_pattern(ArvFakeCamera* camera, ArvFakeCameraFillPattern callback, void* user_data) {
#if ARAVIS_CHECK_VERSION(0, 9, 0)
  arv_fake_camera_set_fill_pattern(camera, callback, user_data, nullptr);
#else
  arv_fake_camera_set_fill_pattern(camera, callback, user_data);
#endif
}

}  // namespace tactile::camera::detail
