#pragma once
// Procedural textures of the synthetic scenes (internal to the renderer). Every pattern is a pure
// function of the material and the surface coordinates (u, v) in metres, built from integer-hashed
// cells: deterministic, no tables, no state. The shape constants below (mortar width, text-line
// height, ...) only define what a pattern looks like; Material::scale_m sets its size.

#include <cstdint>

#include "cge/sim/scene.hpp"

namespace cge {
namespace sim {
namespace detail {

struct Rgb {
  float r, g, b;
};

inline Rgb operator*(const Rgb& c, float k) { return {c.r * k, c.g * k, c.b * k}; }
inline Rgb operator+(const Rgb& a, const Rgb& b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
inline Rgb mix(const Rgb& a, const Rgb& b, float t) { return a * (1.0f - t) + b * t; }

/// A 32-bit hash of a cell (x, y) and a salt (one multiply-xorshift round; enough for textures).
constexpr std::uint32_t hash_cell(std::int32_t x, std::int32_t y, std::uint32_t salt) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 0x9e3779b1u ^ static_cast<std::uint32_t>(y) * 0x85ebca77u ^ salt;
  h ^= h >> 15;
  h *= 0x2c1b3c6du;
  h ^= h >> 13;
  return h;
}

/// Another independent-looking hash from one value.
constexpr std::uint32_t rehash(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

/// The top 24 bits of h as a float in [0, 1).
inline float unit_float(std::uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

/// floor(x) as an integer; |x| must be well inside the int range (texture_run clamps to 1e5).
inline std::int32_t floor_int(float x) {
  const auto i = static_cast<std::int32_t>(x);
  return i - (x < static_cast<float>(i) ? 1 : 0);
}

/// The smooth-noise table the patterns read (built on first use, then shared and read-only).
const std::uint8_t* noise_table();

/// The colours of `material` at n surface points (x[i], y[i]) in cells of the pattern (metres
/// divided by Material::scale_m), times light[i], interleaved as b, g, r into bgr_out (3 n floats);
/// `table` is noise_table().
void texture_run(const Material& material, const float* x, const float* y, const float* light, int n,
                 const std::uint8_t* table, float* bgr_out);

}  // namespace detail
}  // namespace sim
}  // namespace cge
