#pragma once
// The colours of the semantic maps: ten preset colours for COCO classes common indoors, grey for
// every other class and for unlabelled surfaces. The octree stores only colours, so the class of an
// occupied voxel is read back from its colour (class_of_colour); the ten colours are far apart so
// that this stays exact after a round trip through a file.
//
// Class labels follow cge::slam::Keyframe::class_labels: label = COCO class id + 1, 0 = no class.

#include <array>
#include <cstdint>

namespace cge {
namespace mapping {

/// An 8-bit RGB colour (PLY and OctoMap order; OpenCV images are BGR).
struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8& a, const Rgb8& b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
  friend bool operator!=(const Rgb8& a, const Rgb8& b) { return !(a == b); }
  /// 0x00RRGGBB, a total order for sorting and voting.
  std::uint32_t packed() const { return (std::uint32_t(r) << 16) | (std::uint32_t(g) << 8) | std::uint32_t(b); }
};

/// One preset: a COCO class id and its colour.
struct ClassColour {
  int class_id;
  Rgb8 colour;
};

/// The ten preset class colours (COCO ids; the synthetic office uses all of them).
inline constexpr std::array<ClassColour, 10> kPresetClassColours = {{
    {0, {220, 20, 60}},    // person: crimson
    {56, {255, 140, 0}},   // chair: orange
    {57, {138, 43, 226}},  // couch: violet
    {58, {34, 139, 34}},   // potted plant: green
    {60, {139, 69, 19}},   // dining table: brown
    {62, {30, 144, 255}},  // tv: blue
    {63, {0, 206, 209}},   // laptop: turquoise
    {66, {255, 215, 0}},   // keyboard: gold
    {73, {255, 20, 147}},  // book: pink
    {41, {124, 252, 0}},   // cup: lime
}};

/// Colour of every class without a preset and of unlabelled surfaces (walls, floor).
inline constexpr Rgb8 kOtherClassColour{128, 128, 128};

/// True when class label `label` (class id + 1; 0 none) has a preset colour; sets `colour`.
inline bool preset_colour_of_label(std::uint16_t label, Rgb8& colour) {
  if (label == 0) return false;
  for (const ClassColour& c : kPresetClassColours) {
    if (c.class_id + 1 == label) {
      colour = c.colour;
      return true;
    }
  }
  return false;
}

/// The map colour of a class label: its preset colour, else kOtherClassColour.
inline Rgb8 class_colour(std::uint16_t label) {
  Rgb8 c = kOtherClassColour;
  preset_colour_of_label(label, c);
  return c;
}

/// The class label (class id + 1) whose preset colour is `colour`, or 0 when it is no preset colour
/// (grey, or anything else).
inline std::uint16_t class_label_of_colour(const Rgb8& colour) {
  for (const ClassColour& c : kPresetClassColours) {
    if (c.colour == colour) return static_cast<std::uint16_t>(c.class_id + 1);
  }
  return 0;
}

}  // namespace mapping
}  // namespace cge
