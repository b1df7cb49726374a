#pragma once
// A 256-bit binary descriptor (ORB's 32 bytes) as four 64-bit words, and its Hamming distance.
//
// Byte order: byte b of the 32-byte descriptor is bits 8 (b % 8) .. 8 (b % 8) + 7 of word b / 8
// (little-endian within a word), so the conversion from an OpenCV row (cge/opencv/binary_descriptor.hpp)
// is the same on every platform, and bit j of the descriptor is bit j % 64 of word j / 64.

#include <array>
#include <cstdint>
#include <cstring>
#include <string>

namespace cge {
namespace bow {

using BinaryDescriptor = std::array<std::uint64_t, 4>;

/// Bits of a BinaryDescriptor.
constexpr int descriptor_bits = 256;

namespace detail {
inline int popcount64(std::uint64_t x) {
#if (defined(__GNUC__) || defined(__clang__)) && defined(__POPCNT__)
  return __builtin_popcountll(x);  // one instruction
#else
  // Without the POPCNT instruction (baseline x86-64) the builtin is a library call; this bit-sliced
  // count is a dozen inline operations.
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}
}  // namespace detail

/// Number of differing bits, 0 .. 256.
inline int hamming_distance(const BinaryDescriptor& a, const BinaryDescriptor& b) {
  return detail::popcount64(a[0] ^ b[0]) + detail::popcount64(a[1] ^ b[1]) + detail::popcount64(a[2] ^ b[2]) +
         detail::popcount64(a[3] ^ b[3]);
}

/// Hamming distance of two 32-byte descriptor rows (e.g. rows of an OpenCV CV_8UC1 Mat), 0 .. 256.
/// (The words take the host's byte order, not descriptor_from_bytes's: a distance does not care.)
inline int hamming_distance_32_bytes(const std::uint8_t* a, const std::uint8_t* b) {
  BinaryDescriptor x, y;
  std::memcpy(x.data(), a, sizeof x);
  std::memcpy(y.data(), b, sizeof y);
  return hamming_distance(x, y);
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
