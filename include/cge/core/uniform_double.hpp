#pragma once
// Portable uniform doubles from a random engine's raw output.
//
// std::uniform_real_distribution is not portable: libstdc++, libc++ and MSVC turn the same engine
// output into different doubles. Components that draw random numbers therefore derive them here,
// from the engine's raw bits only, so that a seeded engine gives the same doubles everywhere
// (std::mt19937_64 and std::mt19937 are themselves specified bit for bit by the standard).
//
// Contract for the engine E: a uniform random bit generator (operator() returns an unsigned
// integer, static constexpr min() and max()) with min() == 0 and max() == 2^b - 1 for some b in
// [1, 64], i.e. every output carries b random bits. True for std::mt19937, std::mt19937_64,
// std::ranlux24, std::ranlux48 and most modern generators; not for std::minstd_rand (min() == 1).

#include <cstdint>
#include <limits>
#include <type_traits>

namespace cge {

namespace detail {

/// Number of bits b with max() == 2^b - 1, or 0 when max() is not of that form.
constexpr int full_range_bits(std::uint64_t max_value) {
  int bits = 0;
  while (max_value & 1u) {
    max_value >>= 1;
    ++bits;
  }
  return max_value == 0 ? bits : 0;
}

}  // namespace detail

/// Bits of the mantissa a uniform double in [0, 1) is built from.
constexpr int uniform_double_bits = std::numeric_limits<double>::digits;  // 53

/// A uniform double in [0, 1) on the grid k * 2^-53, k = 0 .. 2^53 - 1. The 53 bits are the top
/// bits of as few engine outputs as needed, most significant first: for a 64-bit engine one output
/// x gives (x >> 11) * 2^-53; for a 32-bit engine two outputs a, b give
/// ((a << 21) | (b >> 11)) * 2^-53. Every call consumes exactly ceil(53 / b) outputs.
template <typename Engine>
double uniform_unit_double(Engine& engine) {
  using Result = typename Engine::result_type;
  static_assert(std::is_unsigned<Result>::value && sizeof(Result) <= sizeof(std::uint64_t),
                "uniform_unit_double: the engine must return an unsigned integer of at most 64 bits");
  static_assert(Engine::min() == 0 && detail::full_range_bits(Engine::max()) > 0,
                "uniform_unit_double: the engine's outputs must span 0 .. 2^b - 1 (see cge/core/uniform_double.hpp)");
  constexpr int engine_bits = detail::full_range_bits(Engine::max());
  std::uint64_t mantissa = 0;
  int have = 0;
  while (have < uniform_double_bits) {
    const std::uint64_t raw = static_cast<std::uint64_t>(engine());
    const int take = engine_bits < uniform_double_bits - have ? engine_bits : uniform_double_bits - have;
    mantissa = (mantissa << take) | (raw >> (engine_bits - take));
    have += take;
  }
  // Exact: mantissa < 2^53, and the scale is a power of two.
  constexpr double scale = 1.0 / static_cast<double>(std::uint64_t{1} << uniform_double_bits);
  return static_cast<double>(mantissa) * scale;
}

}  // namespace cge
