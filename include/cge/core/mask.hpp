#pragma once
// Dynamic-object masks as the graph builder reads them.
//
// Contract for a mask type M (specialise cge::traits::Mask<M>):
//   static int  width(const M&), height(const M&)     size in pixels
//   static bool is_set(const M&, int col, int row)    true where a dynamic object covers the pixel
//   static bool empty(const M&)                       true when the mask carries no pixels at all
// An empty mask means "no dynamic objects in this frame" and is accepted for any image size.
// Two types come with the core: BinaryMask (owning, row-major bytes) and NoMask (always empty).
// cv::Mat is adapted in cge/opencv/.

#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cge {

/// Row-major 8-bit mask; any non-zero byte counts as set.
struct BinaryMask {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  ///< width * height bytes, row-major

  BinaryMask() = default;
  BinaryMask(int width_px, int height_px, std::uint8_t fill = 0)
      : width(width_px), height(height_px), pixels(static_cast<std::size_t>(width_px) * height_px, fill) {
    if (width_px < 0 || height_px < 0) throw std::invalid_argument("BinaryMask: negative size");
  }

  std::uint8_t& at(int col, int row) { return pixels[static_cast<std::size_t>(row) * width + col]; }
  std::uint8_t at(int col, int row) const { return pixels[static_cast<std::size_t>(row) * width + col]; }
};

/// The mask of a frame without dynamic objects.
struct NoMask {};

namespace traits {

template <typename M, typename Enable = void>
struct Mask;

template <>
struct Mask<BinaryMask> {
  static int width(const BinaryMask& m) { return m.width; }
  static int height(const BinaryMask& m) { return m.height; }
  static bool is_set(const BinaryMask& m, int col, int row) { return m.at(col, row) != 0; }
  static bool empty(const BinaryMask& m) { return m.pixels.empty(); }
};

template <>
struct Mask<NoMask> {
  static int width(const NoMask&) { return 0; }
  static int height(const NoMask&) { return 0; }
  static bool is_set(const NoMask&, int, int) { return false; }
  static bool empty(const NoMask&) { return true; }
};

}  // namespace traits

/// Throws std::invalid_argument unless the mask is empty or exactly width x height pixels.
template <typename M>
void check_mask_size(const M& mask, int width, int height, const char* which) {
  using T = traits::Mask<M>;
  if (T::empty(mask)) return;
  if (T::width(mask) != width || T::height(mask) != height) {
    std::ostringstream msg;
    msg << which << " is " << T::width(mask) << " x " << T::height(mask) << " pixels but the image is " << width
        << " x " << height;
    throw std::invalid_argument(msg.str());
  }
}

}  // namespace cge
