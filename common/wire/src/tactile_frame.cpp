#include "tactile/wire/tactile_frame.hpp"

#include <cmath>

namespace tactile::wire {

void fill_tactile_frame(const std::string& sensor_id, const FrameHeader& h,
                        std::span<const ElementReading> readings, double mm_per_px,
                        v1::TactileFrame& out) {
  out.set_sensor_id(sensor_id);
  out.set_sequence(h.sequence);
  out.set_camera_frame_id(h.camera_frame_id);
  out.set_camera_timestamp_ns(h.camera_timestamp_ns);
  out.set_receive_timestamp_ns(h.receive_timestamp_ns);
  out.set_publish_timestamp_ns(h.publish_timestamp_ns);
  out.set_status(h.status);
  out.set_nominal_period_ns(h.nominal_period_ns);
  out.set_frames_skipped(h.frames_skipped);
  out.set_measure_time_us(h.measure_time_us);
  auto* elements = out.mutable_elements();
  const int n = h.status == v1::FRAME_STATUS_COMPLETE ? static_cast<int>(readings.size()) : 0;
  // Keep the element messages allocated: shrink by removing the tail, grow by adding.
  while (elements->size() > n)
    elements->RemoveLast();
  while (elements->size() < n)
    elements->Add();
  for (int i = 0; i < n; ++i) {
    const ElementReading& r = readings[static_cast<std::size_t>(i)];
    v1::ElementReading& e = (*elements)[i];
    e.set_id(r.id);
    e.set_contact(r.contact);
    e.set_g(r.G);
    e.set_x_mm(r.contact ? r.x_px * mm_per_px : 0.0);
    e.set_y_mm(r.contact ? r.y_px * mm_per_px : 0.0);
    e.set_dx_mm(r.dx_mm);
    e.set_dy_mm(r.dy_mm);
    e.set_ux_mm(r.ux_mm);
    e.set_uy_mm(r.uy_mm);
    e.set_fx_n(r.fx);
    e.set_fy_n(r.fy);
    e.set_fz_n(r.fz);
    e.set_has_displacement(r.has_displacement);
  }
}

namespace {

// One element into core units, centroids scaled by `px_per_mm`; false when a number is not
// finite (also once scaled) or G is negative.
bool read_element(const v1::ElementReading& e, double px_per_mm, ElementReading& r) noexcept {
  const double values[] = {e.g(),     e.x_mm(),  e.y_mm(), e.dx_mm(), e.dy_mm(),
                           e.ux_mm(), e.uy_mm(), e.fx_n(), e.fy_n(),  e.fz_n()};
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  if (e.g() < 0) return false;
  // A finite centroid in mm can still overflow to infinity in pixels (fuzzing found
  // y_mm = -1.5e308): the core's units must be finite too.
  const double x_px = e.x_mm() * px_per_mm;
  const double y_px = e.y_mm() * px_per_mm;
  if (!std::isfinite(x_px) || !std::isfinite(y_px)) return false;
  r.id = e.id();
  r.contact = e.contact();
  r.has_displacement = e.has_displacement() && e.contact();
  r.G = e.g();
  r.x_px = x_px;
  r.y_px = y_px;
  r.dx_mm = e.dx_mm();
  r.dy_mm = e.dy_mm();
  r.ux_mm = e.ux_mm();
  r.uy_mm = e.uy_mm();
  r.fx = e.fx_n();
  r.fy = e.fy_n();
  r.fz = e.fz_n();
  return true;
}

// `out` resized to `n` readings (no allocation when it has them); false when memory runs out.
bool sized(std::vector<ElementReading>& out, std::size_t n) noexcept {
  if (out.size() == n) return true;
  try {
    out.resize(n);
  } catch (...) {
    return false;
  }
  return true;
}

}  // namespace

DecodeStatus read_tactile_frame(const v1::TactileFrame& in, const Calibration& cal,
                                ReceivedFrame& out) noexcept {
  FrameHeader& h = out.header;
  h.sequence = in.sequence();
  h.camera_frame_id = in.camera_frame_id();
  h.camera_timestamp_ns = in.camera_timestamp_ns();
  h.receive_timestamp_ns = in.receive_timestamp_ns();
  h.publish_timestamp_ns = in.publish_timestamp_ns();
  h.status = in.status();
  h.nominal_period_ns = in.nominal_period_ns();
  h.frames_skipped = in.frames_skipped();
  h.measure_time_us = in.measure_time_us();
  if (!v1::FrameStatus_IsValid(h.status) || !std::isfinite(h.measure_time_us))
    return DecodeStatus::kInvalid;
  if (!sized(out.elements, cal.elements.size())) return DecodeStatus::kInvalid;
  if (h.status != v1::FRAME_STATUS_COMPLETE) {
    return in.elements_size() == 0 ? DecodeStatus::kOk : DecodeStatus::kInvalid;
  }
  if (static_cast<std::size_t>(in.elements_size()) != cal.elements.size())
    return DecodeStatus::kInvalid;
  const double px_per_mm = 1.0 / cal.mm_per_px;
  for (int i = 0; i < in.elements_size(); ++i) {
    const v1::ElementReading& e = in.elements(i);
    const auto k = static_cast<std::size_t>(i);
    if (e.id() != cal.elements[k].id || !read_element(e, px_per_mm, out.elements[k]))
      return DecodeStatus::kInvalid;
  }
  return DecodeStatus::kOk;
}

DecodeStatus read_elements(const v1::TactileFrame& in, std::vector<ElementReading>& out) noexcept {
  if (in.status() != v1::FRAME_STATUS_COMPLETE) {
    out.clear();
    return in.elements_size() == 0 ? DecodeStatus::kOk : DecodeStatus::kInvalid;
  }
  const auto n = static_cast<std::size_t>(in.elements_size());
  if (!sized(out, n)) return DecodeStatus::kInvalid;
  for (std::size_t k = 0; k < n; ++k) {
    if (!read_element(in.elements(static_cast<int>(k)), 1.0, out[k])) return DecodeStatus::kInvalid;
  }
  return DecodeStatus::kOk;
}

}  // namespace tactile::wire
