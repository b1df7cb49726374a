#pragma once
// SequenceSpec: everything that defines a synthetic sequence (scene, people, camera, trajectory,
// instances, ground-truth loops, render settings, seed). The presets (cge/sim/presets.hpp) make
// them; tests and users may also build or edit one by hand. SequenceRenderer renders it.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/sim/bodies.hpp"
#include "cge/sim/render_settings.hpp"
#include "cge/sim/scene.hpp"
#include "cge/sim/sequence.hpp"

namespace cge {
namespace sim {

struct SequenceSpec {
  std::string name;  ///< informative (the preset's name)
  PinholeCamera camera;
  double frame_rate_hz = 30;     ///< frame i is at time i / frame_rate_hz (bodies move with it), > 0
  double start_timestamp_s = 0;  ///< timestamp of frame 0 (RenderedFrame::timestamp_s), seconds
  /// Ground-truth camera pose of every frame; its size is the frame count (>= 1).
  std::vector<Eigen::Isometry3d> T_world_camera;
  std::vector<Primitive> static_primitives;  ///< the room and its objects (possibly added mid-sequence)
  std::vector<Person> people;                ///< articulated moving bodies
  /// Every instance any primitive or person uses (ids unique, >= 1; COCO class ids 0 .. 79).
  std::vector<InstanceInfo> instances;
  std::vector<LoopPair> loops;  ///< ground-truth loops (match < query, both frames of the sequence)
  RenderSettings render;
  std::uint64_t seed = 0;  ///< drives the per-frame depth noise and dropout (nothing else at render time)
};

/// Throws std::invalid_argument naming the offending field (e.g. "SequenceSpec.camera.fx_px must
/// be finite and > 0 (got -1)") for an invalid camera, rate, pose, primitive, person, instance table,
/// loop or render setting, and when an id used by a primitive or person is not in `instances`.
void validate_sequence_spec(const SequenceSpec& spec);

/// Throws std::invalid_argument naming `where` for non-finite or non-positive focal lengths, a
/// non-finite principal point, an image size outside 1 .. 16384 pixels, or depth units not > 0.
void validate_camera(const PinholeCamera& camera, const std::string& where);

}  // namespace sim
}  // namespace cge
