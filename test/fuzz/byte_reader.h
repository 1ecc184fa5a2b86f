// Structured fuzz input: messages built field by field from the bytes (not ROS-deserialized:
// roscpp sizes a vector from its declared length before reading it, so a 10-byte input could ask
// for gigabytes before any of our code runs). Numbers come from a palette of the values that
// break arithmetic (NaN, infinities, 0, tiny, huge) or raw; running out of bytes reads zeros.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace bvh_collision::fuzz {

class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t remaining() const { return size_ - at_; }
  std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t(byte()) << (8 * i);
    return v;
  }
  // Small counts mostly, sometimes anything: 0..max.
  std::size_t count(std::size_t max) { return byte() % (max + 1); }

  double number() {
    static constexpr double kPalette[] = {0.0, 1.0, -1.0, 0.5, 1e-300, 1e300, std::numeric_limits<double>::quiet_NaN(),
                                          std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                                          1e-9, 3.0, -0.5, 0.02, 100.0};
    const std::uint8_t pick = byte();
    if (pick < sizeof(kPalette) / sizeof(kPalette[0])) return kPalette[pick];
    if (pick < 128) {  // raw IEEE bits
      std::uint64_t bits = std::uint64_t(u32()) | std::uint64_t(u32()) << 32;
      double v;
      std::memcpy(&v, &bits, sizeof v);
      return v;
    }
    return (pick - 192) / 32.0;  // -2 .. 2 in steps of 1/32
  }

  // One of `names`, the empty string, or a few raw bytes.
  std::string name(const std::vector<std::string>& names) {
    const std::uint8_t pick = byte();
    if (pick < names.size()) return names[pick];
    if (pick == 255) return "";
    std::string raw(count(12), '\0');
    for (char& c : raw) c = static_cast<char>(byte());
    return raw;
  }

  std::vector<double> numbers(std::size_t max) {
    std::vector<double> v(count(max));
    for (double& x : v) x = number();
    return v;
  }

  // What is left, as bytes.
  std::vector<std::uint8_t> rest() {
    std::vector<std::uint8_t> out(data_ + at_, data_ + size_);
    at_ = size_;
    return out;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

}  // namespace bvh_collision::fuzz
