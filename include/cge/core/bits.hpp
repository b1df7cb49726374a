#pragma once
// Bit helpers shared by the bit-parallel parts (node bitmaps, 64-source lanes).

#include <cstdint>

namespace cge {
namespace detail {

/// Index of the lowest set bit of a non-zero word.
inline int lowest_bit(std::uint64_t word) {
#if defined(__GNUC__) || defined(__clang__)
  return __builtin_ctzll(word);
#else
  int i = 0;
  while (!(word & 1u)) {
    word >>= 1;
    ++i;
  }
  return i;
#endif
}

}  // namespace detail
}  // namespace cge
