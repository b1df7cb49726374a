#pragma once
// SequenceRenderer: renders the frames of a SequenceSpec in memory (RGB, realistic depth, exact
// instance labels, ground-truth pose), any frame in any order.
//
// Method: a z-buffer ray caster. Each primitive's bounding box is projected to the screen (clipped
// at the near plane) and only the rays inside that convex outline are intersected with it; then
// every pixel is shaded once (procedural texture, Lambert + ambient) and the depth-sensor model is
// applied (docs/SIMULATION.md). Rays go through pixel centres: pixel (u, v) looks along
// ((u - cx) / fx, (v - cy) / fy, 1).
//
// Determinism: render(i) is a function of the spec and i only. The depth noise and dropout of
// pixel p of frame i come from hashes of p under a key derived from (spec.seed, i) by splitmix64
// (counter-based: no engine state carried between pixels or frames). No threads, no OpenCV calls
// that may use threads: same spec and index, bit-identical images.
// The renderer is immutable after construction; render() is safe to call from several threads,
// render_into() too when each thread has its own workspace and frame.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/sim/scene.hpp"
#include "cge/sim/sequence.hpp"
#include "cge/sim/sequence_spec.hpp"

namespace cge {
namespace sim {

namespace detail {
/// A primitive prepared for one frame: the camera ray in the primitive's local frame (scaled to a
/// unit sphere for ellipsoids) as an affine function of the pixel, and its screen rectangle.
struct PreparedPrimitive {
  Shape shape = Shape::box;
  std::uint16_t instance_id = 0;
  const Material* material = nullptr;
  float origin[3] = {0, 0, 0};  ///< camera centre in local coordinates
  float dir_u[3] = {0, 0, 0};   ///< ray direction in local coordinates: dir_0 + u dir_u + v dir_v
  float dir_v[3] = {0, 0, 0};
  float dir_0[3] = {0, 0, 0};
  float size[3] = {0, 0, 0};                 ///< half sizes, radii, or (radius, -, half length)
  float light[3] = {0, 0, 0};                ///< key-light direction in local coordinates
  float metric[3] = {1, 1, 1};               ///< local direction times this is metric (ellipsoids: the radii)
  float inv_size[3] = {0, 0, 0};             ///< 1 / size (0 where the size is 0)
  float face_light[6] = {0, 0, 0, 0, 0, 0};  ///< shading of flat face 2k + (normal along +e_k)
  float texture_scale = 1;                   ///< 1 / Material::scale_m
  int v_begin = 0, v_end = 0;                ///< rows [begin, end) the primitive may cover
  std::size_t span_offset = 0;  ///< row v covers columns [spans[o + 2 (v - v_begin)], spans[o + 2 (v - v_begin) + 1])
};
}  // namespace detail

/// Buffers reused by render_into. After a call, depth_exact_m holds that frame's exact depth.
struct RenderWorkspace {
  /// CV_32FC1, the noise-free depth z in metres of the nearest surface at each pixel centre (what
  /// the sensor model starts from), +infinity where the ray hits nothing.
  cv::Mat depth_exact_m;
  // Scratch (not an interface).
  cv::Mat primitive_index;  ///< CV_32SC1, index into `prepared` of the nearest surface, -1 for none
  cv::Mat measurable;       ///< CV_8UC1, 1 where the surface is not seen too obliquely for depth
  std::vector<Primitive> people_primitives;
  std::vector<const Primitive*> frame_primitives;
  std::vector<detail::PreparedPrimitive> prepared;
  std::vector<std::int32_t> spans;
  std::vector<float> largest_jump;                         ///< one row
  std::vector<float> row_x, row_y, row_light, row_colour;  ///< one run of a row
};

class SequenceRenderer {
 public:
  /// Validates the spec (validate_sequence_spec) and keeps it.
  explicit SequenceRenderer(SequenceSpec spec);

  int frame_count() const { return static_cast<int>(spec_.T_world_camera.size()); }
  const SequenceSpec& spec() const { return spec_; }
  const PinholeCamera& camera() const { return spec_.camera; }
  double frame_rate_hz() const { return spec_.frame_rate_hz; }
  const std::vector<InstanceInfo>& instances() const { return spec_.instances; }
  const std::vector<LoopPair>& loops() const { return spec_.loops; }

  /// Time of frame `index` since frame 0 (what the bodies move with), seconds.
  double time_s(int index) const { return index / spec_.frame_rate_hz; }

  /// Frame `index` (0 <= index < frame_count(), else std::invalid_argument).
  RenderedFrame render(int index) const;

  /// The same into existing buffers (reallocated only when their size or type is wrong), for loops
  /// that render many frames: the frame's images are overwritten in place, so clone them to keep
  /// a frame. workspace.depth_exact_m holds the exact depth afterwards.
  void render_into(int index, RenderedFrame& frame, RenderWorkspace& workspace) const;

  /// Every primitive present in frame `index`, in world coordinates (static ones, those added by
  /// then, and the posed people), as the frame is rendered from them.
  std::vector<Primitive> primitives_at(int index) const;

 private:
  void check_index(int index) const;
  void collect_primitives(int index, RenderWorkspace& workspace) const;
  void shade(RenderWorkspace& workspace, RenderedFrame& frame) const;
  void measure_depth(int index, RenderWorkspace& workspace, RenderedFrame& frame) const;

  SequenceSpec spec_;
};

}  // namespace sim
}  // namespace cge
