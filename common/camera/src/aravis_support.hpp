#pragma once

// Private helpers around Aravis and GLib: ownership of GObjects, GError to exception, and the
// process-wide arv_shutdown() once the last Aravis user is gone.
#include <arv.h>

#include <memory>
#include <string_view>

#include "tactile/image.hpp"

namespace tactile::camera::detail {

struct GObjectUnref {
  void operator()(void* object) const noexcept {
    if (object != nullptr) g_object_unref(object);
  }
};
// Owns one reference ("transfer full" results only; never the "transfer none" getters).
template <typename T>
using GPtr = std::unique_ptr<T, GObjectUnref>;

// Throws std::runtime_error "<what>: <error message>" and frees the error, when set.
void throw_if_error(GError* error, std::string_view what);
// Frees a set error; returns its message prefixed by `what`, or an empty string.
std::string take_error(GError* error, std::string_view what);

// Held by every object that uses Aravis; the last one to go calls arv_shutdown() (after its
// own objects are released), so no Aravis thread or interface is left behind.
class AravisUse {
 public:
  AravisUse();
  ~AravisUse();
  AravisUse(const AravisUse&) = delete;
  AravisUse& operator=(const AravisUse&) = delete;
};

ArvPixelFormat to_arv(PixelFormat format);
// Size in bytes of one frame computed from its geometry (never from arv_buffer_get_data inside
// a fill callback: it reports 0 there, Aravis issue 955). 0 for formats we do not serve.
std::size_t frame_bytes(int width, int height, ArvPixelFormat format);

// arv_fake_camera_set_fill_pattern behind one shim: Aravis 0.9 adds a destroy-notify argument.
void set_fill_pattern(ArvFakeCamera* camera, ArvFakeCameraFillPattern callback, void* user_data);

}  // namespace tactile::camera::detail
