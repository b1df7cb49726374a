#include "texture.hpp"

#include <algorithm>
#include <array>
#include <vector>

namespace cge {
namespace sim {
namespace detail {
namespace {

// Smooth noise comes from one table of fractal value noise (three octaves, made once per process),
// read with bilinear interpolation: one table read per pixel instead of hashing lattice corners.
constexpr std::int32_t kFractalSide = 512;  // texels per side of the periodic table
constexpr std::int32_t kTexelsPerCell = 8;  // texels per cell of the first octave
constexpr std::int32_t kFractalMask = kFractalSide - 1;
constexpr std::int32_t kPeriodCells = kFractalSide / kTexelsPerCell;  // the table repeats every 64 cells

/// Value noise with cells of side 1 that repeats every `period` cells (smoothstep interpolation).
float periodic_value_noise(float x, float y, std::int32_t period, std::uint32_t salt) {
  const std::int32_t ix = floor_int(x);
  const std::int32_t iy = floor_int(y);
  float fx = x - static_cast<float>(ix);
  float fy = y - static_cast<float>(iy);
  fx = fx * fx * (3.0f - 2.0f * fx);
  fy = fy * fy * (3.0f - 2.0f * fy);
  auto corner = [&](std::int32_t cx, std::int32_t cy) {
    return unit_float(hash_cell(((cx % period) + period) % period, ((cy % period) + period) % period, salt));
  };
  const float top = corner(ix, iy) + (corner(ix + 1, iy) - corner(ix, iy)) * fx;
  const float bottom = corner(ix, iy + 1) + (corner(ix + 1, iy + 1) - corner(ix, iy + 1)) * fx;
  return top + (bottom - top) * fy;
}

std::vector<std::uint8_t> make_fractal_table() {
  constexpr int kOctaves = 3;
  constexpr float kWeights[kOctaves] = {0.55f, 0.3f, 0.15f};
  std::vector<std::uint8_t> table(static_cast<std::size_t>(kFractalSide) * kFractalSide);
  for (std::int32_t ty = 0; ty < kFractalSide; ++ty) {
    for (std::int32_t tx = 0; tx < kFractalSide; ++tx) {
      float value = 0;
      for (int k = 0; k < kOctaves; ++k) {
        const std::int32_t frequency = 1 << k;
        const float x = static_cast<float>(tx * frequency) / kTexelsPerCell;
        const float y = static_cast<float>(ty * frequency) / kTexelsPerCell;
        value += kWeights[k] *
                 periodic_value_noise(x, y, kPeriodCells * frequency, 0x2545f491u + static_cast<std::uint32_t>(k));
      }
      table[static_cast<std::size_t>(ty * kFractalSide + tx)] = static_cast<std::uint8_t>(value * 255.0f + 0.5f);
    }
  }
  return table;
}

/// Smooth fractal noise in [0, 1] with features from 1 down to 1/4 cell; the salt picks the window.
inline float noise01(const std::uint8_t* table, float x, float y, std::uint32_t salt) {
  // Fixed point with 8 fractional bits: one conversion per axis gives the texel and the fraction
  // (the conversion truncates: 1/256 texel off below zero, invisible). |x| <= 1e5 cells fits int32.
  constexpr float kFixed = 256.0f * kTexelsPerCell;
  const auto fx_fixed = static_cast<std::int32_t>(x * kFixed);
  const auto fy_fixed = static_cast<std::int32_t>(y * kFixed);
  const std::int32_t fx = fx_fixed & 0xFF;
  const std::int32_t fy = fy_fixed & 0xFF;
  const std::int32_t x0 = ((fx_fixed >> 8) + static_cast<std::int32_t>(salt & 0x1FFu)) & kFractalMask;
  const std::int32_t y0 = ((fy_fixed >> 8) + static_cast<std::int32_t>((salt >> 9) & 0x1FFu)) & kFractalMask;
  const std::int32_t x1 = (x0 + 1) & kFractalMask;
  const std::uint8_t* row0 = table + y0 * kFractalSide;
  const std::uint8_t* row1 = table + ((y0 + 1) & kFractalMask) * kFractalSide;
  // Bilinear interpolation in integers (8 + 8 fractional bits), one conversion at the end.
  const std::int32_t top = (row0[x0] << 8) + (row0[x1] - row0[x0]) * fx;
  const std::int32_t bottom = (row1[x0] << 8) + (row1[x1] - row1[x0]) * fx;
  const std::int32_t value = (top << 8) + (bottom - top) * fy;
  return static_cast<float>(value) * (1.0f / (255.0f * 65536.0f));
}

// Strong colours for posters, book spines and screens (RGB).
constexpr std::array<Rgb, 8> kPalette = {{{0.80f, 0.15f, 0.12f},
                                          {0.12f, 0.30f, 0.75f},
                                          {0.95f, 0.80f, 0.15f},
                                          {0.15f, 0.60f, 0.25f},
                                          {0.95f, 0.50f, 0.10f},
                                          {0.95f, 0.95f, 0.92f},
                                          {0.08f, 0.08f, 0.10f},
                                          {0.50f, 0.20f, 0.60f}}};

Rgb to_rgb(const Eigen::Vector3f& c) { return {c.x(), c.y(), c.z()}; }

struct Cell {
  std::int32_t col, row;
  float fu, fv;  // position inside the cell, [0, 1)
};

Cell cell_of(float x, float y) {
  Cell c;
  c.col = floor_int(x);
  c.row = floor_int(y);
  c.fu = x - static_cast<float>(c.col);
  c.fv = y - static_cast<float>(c.row);
  return c;
}

float clamp01(float x) {
  x = x < 0.0f ? 0.0f : x;
  return x > 1.0f ? 1.0f : x;
}

Rgb plain(const Material& m, float x, float y, const std::uint8_t* t) {
  constexpr float kMottle = 0.12f;  // relative brightness variation
  const float n = noise01(t, x, y, m.salt);
  return to_rgb(m.colour_a) * (1.0f - 0.5f * kMottle + kMottle * n);
}

Rgb noise(const Material& m, float x, float y, const std::uint8_t* t) {
  constexpr float kContrast = 2.2f;
  // Speckles: in some cells of a quarter the pattern's size, a dark spot (stucco, fabric slubs),
  // which gives corner detectors something to hold on to in otherwise smooth noise.
  constexpr float kSpotsPerCell = 4.0f;
  constexpr std::uint32_t kSpotOdds = 5;  // one cell in kSpotOdds has a spot
  constexpr float kSpotRadius = 0.3f;     // of a spot cell
  constexpr float kSpotShade = 0.55f;
  const float n = noise01(t, x, y, m.salt);
  const Rgb base = mix(to_rgb(m.colour_a), to_rgb(m.colour_b), clamp01((n - 0.5f) * kContrast + 0.5f));
  const Cell c = cell_of(x * kSpotsPerCell, y * kSpotsPerCell);
  const std::uint32_t h = hash_cell(c.col, c.row, m.salt ^ 0x5f3759dfu);
  const float du = c.fu - 0.5f, dv = c.fv - 0.5f;
  const bool spot = h % kSpotOdds == 0 && du * du + dv * dv < kSpotRadius * kSpotRadius;
  return spot ? base * kSpotShade : base;
}

Rgb bricks(const Material& m, float x, float y, const std::uint8_t* t) {
  constexpr float kHeight = 0.4f;   // brick height / length
  constexpr float kMortar = 0.05f;  // mortar width / brick length
  const std::int32_t row = floor_int(y / kHeight);
  const float shifted = x + ((row & 1) != 0 ? 0.5f : 0.0f);
  const std::int32_t col = floor_int(shifted);
  const float fu = shifted - static_cast<float>(col);
  const float fv = y - static_cast<float>(row) * kHeight;
  if (fu < kMortar || fv < kMortar) return to_rgb(m.colour_b);
  const float shade = 0.65f + 0.55f * unit_float(hash_cell(col, row, m.salt));
  const float grain = 0.88f + 0.24f * noise01(t, x * 7.0f, y * 7.0f, m.salt);
  return to_rgb(m.colour_a) * (shade * grain);
}

Rgb planks(const Material& m, float x, float y, const std::uint8_t* t) {
  constexpr float kLength = 5.0f;  // plank length / width
  constexpr float kJoint = 0.04f;  // joint width / plank width
  const std::int32_t row = floor_int(y);
  const float shifted = x + kLength * unit_float(hash_cell(row, 0, m.salt + 7));
  const std::int32_t col = floor_int(shifted / kLength);
  const float fu = shifted - static_cast<float>(col) * kLength;
  const float fv = y - static_cast<float>(row);
  if (fu < kJoint || fv < kJoint) return to_rgb(m.colour_b);
  const float shade = 0.7f + 0.5f * unit_float(hash_cell(col, row, m.salt));
  const float grain = 0.78f + 0.4f * noise01(t, x * 1.3f + 31.0f * static_cast<float>(row), y * 15.0f, m.salt);
  return to_rgb(m.colour_a) * (shade * grain);
}

Rgb tiles(const Material& m, float x, float y, const std::uint8_t* t) {
  constexpr float kGrout = 0.07f;  // grout width / tile side
  const Cell c = cell_of(x, y);
  if (c.fu < kGrout || c.fv < kGrout) return to_rgb(m.colour_b);
  const float shade = 0.78f + 0.4f * unit_float(hash_cell(c.col, c.row, m.salt));
  return to_rgb(m.colour_a) * (shade * (0.95f + 0.1f * noise01(t, x * 5.0f, y * 5.0f, m.salt)));
}

Rgb blocks(const Material& m, float x, float y) {
  const Cell c = cell_of(x, y);
  const std::uint32_t h1 = hash_cell(c.col, c.row, m.salt);
  const std::uint32_t h2 = rehash(h1);
  const std::uint32_t h3 = rehash(h2);
  const Rgb background = mix(to_rgb(m.colour_a), to_rgb(m.colour_b), 0.6f * unit_float(h1));
  const Rgb ink = kPalette[(h2 >> 3) & 7u];
  const float x0 = 0.08f + 0.35f * unit_float(h3);
  const float x1 = x0 + 0.25f + 0.3f * unit_float(rehash(h3));
  const float y0 = 0.08f + 0.35f * unit_float(h2);
  const float y1 = y0 + 0.25f + 0.3f * unit_float(rehash(h1 ^ 0x1234567u));
  const bool in_box = c.fu >= x0 && c.fu <= x1 && c.fv >= y0 && c.fv <= y1;
  switch (h2 & 3u) {
    case 0:  // filled rectangle
      return in_box ? ink : background;
    case 1: {  // disc
      const float du = c.fu - 0.5f * (x0 + x1);
      const float dv = c.fv - 0.5f * (y0 + y1);
      const float r = 0.5f * (x1 - x0);
      return du * du + dv * dv <= r * r ? ink : background;
    }
    case 2:  // stripes inside the rectangle
      return in_box && (floor_int(c.fv * 9.0f) & 1) == 0 ? ink : background;
    default: {  // frame with a differently coloured inside
      const bool inner = c.fu >= x0 + 0.06f && c.fu <= x1 - 0.06f && c.fv >= y0 + 0.06f && c.fv <= y1 - 0.06f;
      if (!in_box) return background;
      return inner ? kPalette[(h3 >> 5) & 7u] : ink;
    }
  }
}

Rgb checks(const Material& m, float x, float y) {
  constexpr float kBandsPerCell = 2.0f;
  constexpr float kLine = 0.14f;  // dark line width / band width
  const Rgb a = to_rgb(m.colour_a);
  const Rgb b = to_rgb(m.colour_b);
  const std::array<Rgb, 4> band_colours = {a, b, a * 0.35f, mix(a, b, 0.5f)};
  const Cell cu = cell_of(x * kBandsPerCell, 0.0f);
  const Cell cv = cell_of(y * kBandsPerCell, 0.0f);
  const Rgb along_u = band_colours[hash_cell(cu.col, 11, m.salt) & 3u];
  const Rgb along_v = band_colours[hash_cell(cv.col, 23, m.salt) & 3u];
  Rgb c = mix(along_u, along_v, 0.5f);
  if ((cu.col % 3 == 0 && cu.fu < kLine) || (cv.col % 3 == 0 && cv.fu < kLine)) c = c * 0.45f;
  return c;
}

Rgb spines(const Material& m, float x, float y) {
  constexpr float kGap = 0.06f;         // dark gap between books / spine width
  constexpr float kBandPeriod = 4.0f;   // title bands repeat every this many spine widths upwards
  constexpr float kBandHeight = 0.12f;  // fraction of the period
  const Cell c = cell_of(x, 0.0f);
  if (c.fu < kGap) return to_rgb(m.colour_b) * 0.3f;
  const std::uint32_t h = hash_cell(c.col, 0, m.salt);
  Rgb spine = mix(kPalette[h & 7u], to_rgb(m.colour_a), 0.3f * unit_float(rehash(h)));
  const float band = y / kBandPeriod + unit_float(rehash(h + 1));
  const float fb = band - static_cast<float>(floor_int(band));
  if (fb < kBandHeight) spine = kPalette[(h >> 4) & 7u];
  return spine;
}

Rgb screen(const Material& m, float x, float y, const std::uint8_t* t) {
  constexpr float kWindowWidth = 3.0f;  // window cell, in scale units
  constexpr float kWindowHeight = 2.0f;
  constexpr float kLineHeight = 0.16f;  // text line, in scale units
  constexpr float kWordWidth = 0.45f;
  const Rgb desktop = to_rgb(m.colour_b);
  const Cell w = cell_of(x / kWindowWidth, y / kWindowHeight);
  const std::uint32_t h = hash_cell(w.col, w.row, m.salt);
  const float margin = 0.04f + 0.12f * unit_float(h);
  if (w.fu < margin || w.fu > 1.0f - margin * 0.5f || w.fv < margin || w.fv > 1.0f - margin * 0.7f) {
    return desktop * (0.9f + 0.2f * noise01(t, x, y, m.salt));
  }
  if (w.fv > 1.0f - margin * 0.7f - 0.08f) return to_rgb(m.colour_a);  // title bar
  const Cell line = cell_of(x / kWordWidth, y / kLineHeight);
  const std::uint32_t word = hash_cell(line.col, line.row, m.salt + 5);
  const bool ink = line.fv > 0.3f && line.fv < 0.8f && line.fu < 0.2f + 0.75f * unit_float(word) && (word & 7u) != 0;
  return ink ? Rgb{0.35f, 0.35f, 0.4f} : Rgb{0.88f, 0.88f, 0.86f};
}

Rgb leaves(const Material& m, float x, float y) {
  constexpr float kMaxRadius = 0.75f;  // leaf radius / cell side
  const Cell c = cell_of(x, y);
  std::uint32_t best = 0;
  bool found = false;
  for (std::int32_t dr = -1; dr <= 1; ++dr) {
    for (std::int32_t dc = -1; dc <= 1; ++dc) {
      const std::uint32_t h = hash_cell(c.col + dc, c.row + dr, m.salt);
      const float cx = static_cast<float>(dc) + unit_float(h);
      const float cy = static_cast<float>(dr) + unit_float(rehash(h));
      const float r = kMaxRadius * (0.5f + 0.5f * unit_float(rehash(h + 3)));
      const float du = c.fu - cx;
      const float dv = (c.fv - cy) * 1.6f;  // elongated leaves
      if (du * du + dv * dv <= r * r && (!found || h > best)) {
        best = h;
        found = true;
      }
    }
  }
  if (!found) return to_rgb(m.colour_b);
  return to_rgb(m.colour_a) * (0.55f + 0.7f * unit_float(best));
}

}  // namespace

const std::uint8_t* noise_table() {
  static const std::vector<std::uint8_t> table = make_fractal_table();
  return table.data();
}

namespace {

/// Applies one pattern to a run of points (the pattern's code inlined into the loop), scaled by
/// the light and stored as b, g, r.
template <typename Pattern>
void run(const float* x, const float* y, const float* light, int n, float* bgr_out, Pattern pattern) {
  // Keep cell coordinates where float-to-int conversions are exact and defined.
  constexpr float kLimit = 1e5f;
  for (int i = 0; i < n; ++i) {
    const float xi = std::min(std::max(x[i], -kLimit), kLimit);
    const float yi = std::min(std::max(y[i], -kLimit), kLimit);
    const Rgb c = pattern(xi, yi);
    bgr_out[3 * i] = c.b * light[i];
    bgr_out[3 * i + 1] = c.g * light[i];
    bgr_out[3 * i + 2] = c.r * light[i];
  }
}

}  // namespace

void texture_run(const Material& m, const float* x, const float* y, const float* light, int n, const std::uint8_t* t,
                 float* bgr_out) {
  switch (m.pattern) {
    case Pattern::plain:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return plain(m, a, b, t); });
    case Pattern::noise:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return noise(m, a, b, t); });
    case Pattern::bricks:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return bricks(m, a, b, t); });
    case Pattern::planks:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return planks(m, a, b, t); });
    case Pattern::tiles:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return tiles(m, a, b, t); });
    case Pattern::blocks:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return blocks(m, a, b); });
    case Pattern::checks:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return checks(m, a, b); });
    case Pattern::spines:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return spines(m, a, b); });
    case Pattern::screen:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return screen(m, a, b, t); });
    case Pattern::leaves:
      return run(x, y, light, n, bgr_out, [&](float a, float b) { return leaves(m, a, b); });
  }
}

}  // namespace detail
}  // namespace sim
}  // namespace cge
