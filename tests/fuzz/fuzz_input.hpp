#pragma once

// Reads typed values from a fuzzer's bytes; past the end every value is 0.
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace tactile::fuzz {

class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t left() const { return size_ - pos_; }
  std::uint8_t u8() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() {
    return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16);
  }
  std::uint64_t u64() {
    return static_cast<std::uint64_t>(u32()) | (static_cast<std::uint64_t>(u32()) << 32);
  }
  bool bit() { return (u8() & 1) != 0; }
  // Any double, NaN and infinities included.
  double raw_double() {
    const std::uint64_t bits = u64();
    double d = 0;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  // Mostly ordinary numbers in [lo, hi], sometimes any double at all.
  double number(double lo, double hi) {
    const std::uint8_t mode = u8();
    if (mode < 16) return raw_double();
    return lo + (hi - lo) * (u16() / 65535.0);
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace tactile::fuzz
