#include "tactile/util/pgm.hpp"

#include <cctype>
#include <stdexcept>

#include "tactile/util/files.hpp"

namespace tactile::util {
namespace {

class HeaderReader {
 public:
  HeaderReader(std::string_view b, const std::string& source) : b_(b), source_(source) {}

  void skip_space_and_comments() {
    while (pos_ < b_.size()) {
      const char c = b_[pos_];
      if (c == '#') {
        while (pos_ < b_.size() && b_[pos_] != '\n')
          ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos_;
      } else {
        break;
      }
    }
  }

  long number(const char* what) {
    skip_space_and_comments();
    long v = 0;
    std::size_t digits = 0;
    while (pos_ < b_.size() && std::isdigit(static_cast<unsigned char>(b_[pos_]))) {
      v = v * 10 + (b_[pos_] - '0');
      if (v > 1000000) fail(std::string(what) + " is too large");
      ++pos_;
      ++digits;
    }
    if (digits == 0) fail(std::string("header has no ") + what);
    return v;
  }

  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(source_ + ": not a valid binary PGM (P5) image: " + why);
  }

  std::size_t pos_ = 0;
  std::string_view b_;
  const std::string& source_;
};

}  // namespace

Image decode_pgm(std::string_view bytes, const std::string& source) {
  HeaderReader h(bytes, source);
  if (bytes.size() < 2 || bytes[0] != 'P' || bytes[1] != '5') {
    h.fail("it does not start with 'P5'");
  }
  h.pos_ = 2;
  const long width = h.number("width");
  const long height = h.number("height");
  const long maxval = h.number("maxval");
  if (width <= 0 || height <= 0) h.fail("width and height must be positive");
  if (maxval <= 0 || maxval > 65535)
    h.fail("maxval must be 1..65535, is " + std::to_string(maxval));
  if (h.pos_ >= bytes.size() || !std::isspace(static_cast<unsigned char>(bytes[h.pos_]))) {
    h.fail("no white space after maxval");
  }
  ++h.pos_;
  const PixelFormat fmt = maxval <= 255 ? PixelFormat::kMono8 : PixelFormat::kMono16;
  const auto w = static_cast<int>(width);
  const auto ht = static_cast<int>(height);
  const std::size_t need =
      static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * bytes_per_pixel(fmt);
  if (bytes.size() - h.pos_ < need) {
    h.fail("pixel data is truncated: " + std::to_string(bytes.size() - h.pos_) + " of " +
           std::to_string(need) + " bytes");
  }
  Image img(w, ht, fmt);
  const auto* src = reinterpret_cast<const unsigned char*>(bytes.data() + h.pos_);
  if (fmt == PixelFormat::kMono8) {
    std::copy(src, src + need, img.bytes().begin());
  } else {
    for (int y = 0; y < ht; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t i = 2 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + x);
        img.set(x, y, (static_cast<std::uint32_t>(src[i]) << 8) | src[i + 1]);
      }
    }
  }
  return img;
}

Image read_pgm(const std::filesystem::path& path) {
  return decode_pgm(read_file(path), path.string());
}

std::string encode_pgm(const ImageView& image) {
  const bool wide = image.format == PixelFormat::kMono16;
  std::string out = "P5\n" + std::to_string(image.width) + " " + std::to_string(image.height) +
                    "\n" + (wide ? "65535" : "255") + "\n";
  const std::size_t header = out.size();
  out.resize(header + static_cast<std::size_t>(image.width) *
                          static_cast<std::size_t>(image.height) * (wide ? 2U : 1U));
  std::size_t i = header;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::uint32_t v = image.at(x, y);
      if (wide) out[i++] = static_cast<char>(v >> 8);
      out[i++] = static_cast<char>(v & 0xFF);
    }
  }
  return out;
}

void write_pgm(const std::filesystem::path& path, const ImageView& image) {
  write_file_atomic(path, encode_pgm(image));
}

}  // namespace tactile::util
