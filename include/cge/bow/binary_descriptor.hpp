#pragma once
// A 256-bit binary descriptor (ORB's 32 bytes) as four 64-bit words, and its Hamming distance.
//
// Byte order: byte b of the 32-byte descriptor is bits 8 (b % 8) .. 8 (b % 8) + 7 of word b / 8
// (little-endian within a word), so the conversion from an OpenCV row (cge/opencv/binary_descriptor.hpp)
// is the same on every platform, and bit j of the descriptor is bit j % 64 of word j / 64.

#include <array>
#include <cstdint>
#include <string>

namespace cge {
namespace bow {

using BinaryDescriptor = std::array<std::uint64_t, 4>;

/// Bits of a BinaryDescriptor.
constexpr int descriptor_bits = 256;

namespace detail {
inline int popcount64(std::uint64_t x) {
#if defined(__GNUC__) || defined(__clang__)
  return __builtin_popcountll(x);
#else
  int n = 0;
  while (x) {
    x &= x - 1;
    ++n;
  }
  return n;
#endif
}
}  // namespace detail

/// Number of differing bits, 0 .. 256.
inline int hamming_distance(const BinaryDescriptor& a, const BinaryDescriptor& b) {
  return detail::popcount64(a[0] ^ b[0]) + detail::popcount64(a[1] ^ b[1]) + detail::popcount64(a[2] ^ b[2]) +
         detail::popcount64(a[3] ^ b[3]);
}

/// Bit j (0 .. 255) of a descriptor.
inline bool descriptor_bit(const BinaryDescriptor& d, int j) {
  return ((d[static_cast<std::size_t>(j / 64)] >> (j % 64)) & 1u) != 0;
}

/// The 32 bytes from a byte array (byte b into word b / 8 at bit 8 (b % 8)).
inline BinaryDescriptor descriptor_from_bytes(const std::uint8_t* bytes) {
  BinaryDescriptor d{0, 0, 0, 0};
  for (int b = 0; b < 32; ++b) {
    d[static_cast<std::size_t>(b / 8)] |= static_cast<std::uint64_t>(bytes[b]) << (8 * (b % 8));
  }
  return d;
}

/// Byte b of a descriptor (the inverse of descriptor_from_bytes).
inline std::uint8_t descriptor_byte(const BinaryDescriptor& d, int b) {
  return static_cast<std::uint8_t>(d[static_cast<std::size_t>(b / 8)] >> (8 * (b % 8)));
}

}  // namespace bow
}  // namespace cge
