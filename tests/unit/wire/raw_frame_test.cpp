// Raw frames: pixels and settings round-trip through tactile.v1.RawFrame unchanged.
#include "tactile/wire/raw_frame.hpp"

#include <gtest/gtest.h>

namespace tactile::wire {
namespace {

TEST(RawFrame, PixelsRoundTripForBothDepthsAndPaddedRows) {
  for (const PixelFormat format : {PixelFormat::kMono8, PixelFormat::kMono16}) {
    const int w = 7;
    const int h = 5;
    const std::size_t bpp = bytes_per_pixel(format);
    const std::size_t stride = w * bpp + 3;  // padded rows, as a camera buffer may have
    std::vector<std::uint8_t> buf(stride * h, 0xEE);
    Image expected(w, h, format);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::uint32_t v =
            format == PixelFormat::kMono8 ? (x * 31 + y * 7) % 256 : (x * 3001 + y * 977) % 65536;
        expected.set(x, y, v);
        if (format == PixelFormat::kMono8) {
          buf[y * stride + x] = static_cast<std::uint8_t>(v);
        } else {
          const auto v16 = static_cast<std::uint16_t>(v);
          std::memcpy(&buf[y * stride + x * 2], &v16, 2);
        }
      }
    }
    const ImageView view{buf.data(), w, h, stride, format, 10, 20};
    v1::RawFrame raw;
    fill_raw_pixels(view, raw);
    EXPECT_EQ(raw.width(), 7U);
    EXPECT_EQ(raw.height(), 5U);
    EXPECT_EQ(raw.bit_depth(), format == PixelFormat::kMono8 ? 8U : 16U);
    EXPECT_EQ(raw.pixels().size(), w * h * bpp);
    if (format == PixelFormat::kMono16) {  // little-endian on the wire
      const auto v = expected.get(1, 0);
      EXPECT_EQ(static_cast<std::uint8_t>(raw.pixels()[2]), v & 0xFF);
      EXPECT_EQ(static_cast<std::uint8_t>(raw.pixels()[3]), v >> 8);
    }
    v1::RawFrame parsed;
    ASSERT_TRUE(parsed.ParseFromString(raw.SerializeAsString()));
    std::vector<std::uint8_t> scratch;
    ImageView back;
    std::string why;
    ASSERT_TRUE(raw_view(parsed, scratch, back, why)) << why;
    EXPECT_EQ(back.origin_x, 10);
    EXPECT_EQ(back.origin_y, 20);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x)
        ASSERT_EQ(back.at(x, y), expected.get(x, y)) << x << "," << y;
    }
  }
}

TEST(RawFrame, ViewRefusesWhatIsNotAnImage) {
  v1::RawFrame raw;
  raw.set_width(4);
  raw.set_height(2);
  raw.set_bit_depth(12);
  raw.set_pixels(std::string(8, '\0'));
  std::vector<std::uint8_t> scratch;
  ImageView v;
  std::string why;
  EXPECT_FALSE(raw_view(raw, scratch, v, why));
  EXPECT_NE(why.find("bit depth 12"), std::string::npos);
  raw.set_bit_depth(16);
  EXPECT_FALSE(raw_view(raw, scratch, v, why));
  EXPECT_NE(why.find("8 pixel bytes for a 4x2 16-bit frame"), std::string::npos) << why;
}

TEST(RawFrame, SettingsRoundTrip) {
  ExtractorOptions o;
  o.estimator = CentroidEstimator::kWindowed;
  o.max_gap_frames = 3;
  o.window_margin_px = 2.5;
  o.gaussian_reach_sigmas = 3.25;
  o.accept_regions = true;
  o.reference_spot_check = false;
  v1::MeasurementSettings s;
  fill_settings(o, s);
  const ExtractorOptions back = to_options(s);
  EXPECT_EQ(back.estimator, o.estimator);
  EXPECT_EQ(back.max_gap_frames, 3U);
  EXPECT_EQ(back.window_margin_px, 2.5);
  EXPECT_EQ(back.gaussian_reach_sigmas, 3.25);
  EXPECT_TRUE(back.accept_regions);
  EXPECT_FALSE(back.reference_spot_check);
  s.set_estimator("magic");
  EXPECT_THROW(to_options(s), std::invalid_argument);
}

}  // namespace
}  // namespace tactile::wire
