// libFuzzer target: the measurement core on a random calibration (validated first; refusals are
// fine), random options and random frames, whole or as regions, with random sequence numbers.
// Any NaN or infinity, negative G, centroid outside its disk, or displacement without contact in
// two frames aborts.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <vector>

#include "fuzz_input.hpp"
#include "tactile/extractor.hpp"

namespace {

using tactile::fuzz::Input;

tactile::PiecewiseLinear curve(Input& in) {
  const int n = 2 + in.u8() % 4;
  std::vector<double> x;
  std::vector<double> y;
  double xs = 0;
  double ys = 0;
  for (int i = 0; i < n; ++i) {
    x.push_back(i == 0 ? 0.0 : (xs += in.number(1e-6, 1e6)));
    y.push_back(i == 0 ? 0.0 : (ys += in.number(0, 1e6)));
  }
  if (in.bit()) x.back() = in.raw_double();
  return {x, y};
}

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  tactile::Calibration cal;
  cal.sensor_id = "fuzz";
  cal.width = 1 + in.u8() % 64;
  cal.height = 1 + in.u8() % 64;
  cal.bit_depth = in.bit() ? 16 : 8;
  const double max_gray = cal.bit_depth == 8 ? 255 : 65535;
  cal.mm_per_px = in.number(1e-6, 10);
  cal.noise_floor = in.number(0, max_gray);
  cal.contact_on = in.number(0, max_gray * 4096);
  cal.contact_off = in.number(0, cal.contact_on);
  cal.normal_curve = curve(in);
  cal.shear_curve = curve(in);
  const int elements = 1 + in.u8() % 6;
  for (int i = 0; i < elements; ++i) {
    tactile::ElementCalibration e;
    e.id = in.u8();
    e.center_px = {in.number(-1, cal.width), in.number(-1, cal.height)};
    e.radius_px = in.number(0, 40);
    e.zero_px = in.bit() ? e.center_px : tactile::Vec2{in.number(-1, 65), in.number(-1, 65)};
    cal.elements.push_back(e);
  }
  tactile::ExtractorOptions opt;
  opt.estimator = static_cast<tactile::CentroidEstimator>(in.u8() % 4);
  opt.reference_frames = 1 + in.u8() % 3;
  opt.reference_spot_check = in.bit();
  opt.max_gap_frames = in.u8() % 6;
  opt.window_margin_px = in.number(0, 8);
  opt.gaussian_reach_sigmas = in.number(0.5, 8);
  opt.accept_regions = in.bit();
  opt.portable_kernels = in.bit();
  std::unique_ptr<tactile::Extractor> ex;
  try {
    ex = std::make_unique<tactile::Extractor>(cal, opt);
  } catch (const tactile::CalibrationError&) {
    return 0;
  } catch (const std::invalid_argument&) {
    return 0;
  }

  const auto fmt =
      cal.bit_depth == 8 ? tactile::PixelFormat::kMono8 : tactile::PixelFormat::kMono16;
  tactile::Image img(cal.width, cal.height, fmt);
  std::vector<tactile::ElementReading> previous;
  std::uint64_t last_seq = 0;
  bool have_previous = false;
  for (int frame = 0; frame < 12 && in.left() > 0; ++frame) {
    // Pixels from the input, a run of one value or raw bytes.
    const std::uint8_t fill = in.u8();
    auto bytes = img.bytes();
    if ((fill & 3) == 0) {
      for (auto& b : bytes)
        b = in.u8();
    } else {
      const std::uint8_t v = in.u8();
      for (std::size_t k = 0; k < bytes.size(); ++k)
        bytes[k] = (fill & 3) == 1 ? v : static_cast<std::uint8_t>(v + k * (fill >> 2));
    }
    tactile::ImageView view = img.view();
    if (in.bit()) {  // part of the frame, anywhere
      const int x0 = in.u8() % cal.width;
      const int y0 = in.u8() % cal.height;
      view.data += static_cast<std::size_t>(y0) * view.stride_bytes +
                   static_cast<std::size_t>(x0) * tactile::bytes_per_pixel(fmt);
      view.width = 1 + in.u8() % (cal.width - x0);
      view.height = 1 + in.u8() % (cal.height - y0);
      view.origin_x = in.bit() ? x0 : static_cast<int>(in.u8()) - 8;
      view.origin_y = in.bit() ? y0 : static_cast<int>(in.u8()) - 8;
    }
    if (!ex->has_reference() || in.u8() < 8) {
      if (in.bit()) ex->begin_reference();
      ex->add_reference_frame(view);
      have_previous = false;
      continue;
    }
    const std::uint64_t seq = in.bit() ? last_seq + in.u8() % 6 : in.u64();
    const tactile::MeasureStatus st = ex->measure(view, {seq, static_cast<std::int64_t>(in.u64())});
    if (st != tactile::MeasureStatus::kOk) continue;
    const auto rd = ex->readings();
    for (std::size_t i = 0; i < rd.size(); ++i) {
      const tactile::ElementReading& r = rd[i];
      const tactile::ElementCalibration& e = cal.elements[i];
      for (double v : {r.G, r.x_px, r.y_px, r.dx_mm, r.dy_mm, r.ux_mm, r.uy_mm, r.fx, r.fy, r.fz})
        check(std::isfinite(v));
      check(r.G >= 0);
      if (r.contact) {
        check(std::hypot(r.x_px - e.center_px.x, r.y_px - e.center_px.y) <= e.radius_px + 1e-9);
      } else {
        check(r.x_px == 0 && r.y_px == 0 && r.fz == 0 && r.fx == 0 && r.fy == 0);
      }
      if (r.has_displacement) {
        check(r.contact && have_previous && previous[i].contact && seq > last_seq);
      } else {
        check(r.dx_mm == 0 && r.dy_mm == 0);
      }
    }
    previous.assign(rd.begin(), rd.end());
    have_previous = true;
    last_seq = seq;
    if (in.u8() < 16) {
      ex->forget_previous();
      have_previous = false;
    }
  }
  return 0;
}
