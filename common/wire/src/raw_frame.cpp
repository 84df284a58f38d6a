#include "tactile/wire/raw_frame.hpp"

#include <bit>
#include <cstring>
#include <stdexcept>

namespace tactile::wire {

void fill_raw_pixels(const ImageView& view, v1::RawFrame& out) {
  const std::size_t bpp = bytes_per_pixel(view.format);
  const std::size_t row = static_cast<std::size_t>(view.width) * bpp;
  const std::size_t height = static_cast<std::size_t>(view.height);
  out.set_width(static_cast<std::uint32_t>(view.width));
  out.set_height(static_cast<std::uint32_t>(view.height));
  out.set_bit_depth(static_cast<std::uint32_t>(bit_depth(view.format)));
  out.set_origin_x(view.origin_x);
  out.set_origin_y(view.origin_y);
  std::string& pixels = *out.mutable_pixels();
  pixels.resize(row * height);
  for (std::size_t y = 0; y < height; ++y) {
    std::memcpy(pixels.data() + y * row, view.data + y * view.stride_bytes, row);
  }
  if constexpr (std::endian::native == std::endian::big) {
    if (bpp == 2) {
      for (std::size_t i = 0; i + 1 < pixels.size(); i += 2)
        std::swap(pixels[i], pixels[i + 1]);
    }
  }
}

bool raw_view(const v1::RawFrame& in, std::vector<std::uint8_t>& scratch, ImageView& out,
              std::string& why) {
  if (in.bit_depth() != 8 && in.bit_depth() != 16) {
    why = "bit depth " + std::to_string(in.bit_depth()) + " (8 or 16)";
    return false;
  }
  if (in.width() == 0 || in.height() == 0 || in.width() > 65536 || in.height() > 65536) {
    why = "size " + std::to_string(in.width()) + "x" + std::to_string(in.height());
    return false;
  }
  const PixelFormat format = in.bit_depth() == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
  const std::size_t row = static_cast<std::size_t>(in.width()) * bytes_per_pixel(format);
  if (in.pixels().size() != row * in.height()) {
    why = std::to_string(in.pixels().size()) + " pixel bytes for a " + std::to_string(in.width()) +
          "x" + std::to_string(in.height()) + " " + std::to_string(in.bit_depth()) + "-bit frame";
    return false;
  }
  const auto* data = reinterpret_cast<const std::uint8_t*>(in.pixels().data());
  if (std::endian::native == std::endian::big && format == PixelFormat::kMono16) {
    scratch.assign(data, data + in.pixels().size());
    for (std::size_t i = 0; i + 1 < scratch.size(); i += 2)
      std::swap(scratch[i], scratch[i + 1]);
    data = scratch.data();
  }
  out = ImageView{data,
                  static_cast<int>(in.width()),
                  static_cast<int>(in.height()),
                  row,
                  format,
                  in.origin_x(),
                  in.origin_y()};
  return true;
}

void fill_settings(const ExtractorOptions& o, v1::MeasurementSettings& out) {
  out.set_estimator(to_string(o.estimator));
  out.set_max_gap_frames(o.max_gap_frames);
  out.set_window_margin_px(o.window_margin_px);
  out.set_gaussian_reach_sigmas(o.gaussian_reach_sigmas);
  out.set_accept_regions(o.accept_regions);
  out.set_reference_spot_check(o.reference_spot_check);
}

ExtractorOptions to_options(const v1::MeasurementSettings& s) {
  ExtractorOptions o;
  const auto estimator = parse_estimator(s.estimator());
  if (!estimator) throw std::invalid_argument("unknown centroid estimator '" + s.estimator() + "'");
  o.estimator = *estimator;
  o.max_gap_frames = s.max_gap_frames();
  o.window_margin_px = s.window_margin_px();
  o.gaussian_reach_sigmas = s.gaussian_reach_sigmas();
  o.accept_regions = s.accept_regions();
  o.reference_spot_check = s.reference_spot_check();
  o.reference_frames = 1;
  return o;
}

}  // namespace tactile::wire
