#pragma once
// Scenario presets mirroring the TUM RGB-D fr3 dynamic sequences, plus two loop scenes
// (docs/SIMULATION.md, "Presets"). All share one office room (about 7 m x 6 m x 2.7 m): desks with
// monitors, keyboards and books, chairs, plants, a bookshelf, a couch, a second table, posters.
//
//   walking_xyz         camera translating along x, y, z; two people walking
//   walking_halfsphere  camera on a half sphere of 1 m diameter looking at the desks; two people walking
//   walking_rpy         camera rotating about roll, pitch, yaw in place; two people walking
//   walking_static      camera almost still; two people walking
//   sitting_xyz         camera translating along x, y, z; two people sitting, moving little
//   loop_dynamic        camera circling the room (laps); a pedestrian crosses in front of it at the
//                       revisited place on every lap after the first
//   loop_structure_change  camera circling the room; objects appear at the revisited place after the
//                       first lap (while the camera looks the other way)
//
// The seed varies the textures, clothes, body heights, paths and trajectory phases, and the depth
// noise; the room layout, the motions' kind and the loops' place stay the same.

#include <cstdint>
#include <string>
#include <vector>

#include "cge/sim/loops.hpp"
#include "cge/sim/render_settings.hpp"
#include "cge/sim/sequence.hpp"
#include "cge/sim/sequence_spec.hpp"

namespace cge {
namespace sim {

/// Most frames a preset makes: 18000, 10 minutes at 30 Hz (TUM's longest RGB-D sequences have a few
/// thousand). It bounds what grows with the length before the first frame renders (poses, the
/// people's paths, the loop scenes' ground-truth loops, which grow faster than the length: about
/// 180 MB at the limit) and keeps the simulated network's false-positive ids, one 16-bit label per
/// frame after the scene's ids, within range.
constexpr int kMaxPresetFrames = 18000;
/// Fastest accepted walking speed, metres per second: a sprinter's (~10 m/s). The people's paths
/// are made of steps, so their memory grows with speed x duration.
constexpr double kMaxWalkingSpeedMps = 10;

struct PresetSettings {
  PinholeCamera camera;            ///< TUM fr3 intrinsics, 640 x 480 by default
  RenderSettings render;           ///< lighting and depth-sensor model
  double frame_rate_hz = 30;       ///< as TUM, > 0
  double start_timestamp_s = 0;    ///< timestamp of frame 0, seconds
  double walking_speed_mps = 1.0;  ///< speed of walking people, metres per second, in (0, kMaxWalkingSpeedMps]
  /// Walking presets: how long the second person stands still at each of its stops, seconds, >= 0
  /// (long pauses let a person enter a map as static before walking on).
  double pause_s = 1.5;
  int loop_laps = 3;               ///< loop scenes: laps of the room, >= 2
  double loop_radius_m = 1.1;      ///< loop scenes: radius of the camera's circle, metres, in (0, 1.6]
  double crossing_time_s = 3.0;    ///< loop_dynamic: time the pedestrian takes to cross, seconds, > 0
  LoopSettings loops;              ///< how the ground-truth loops of the loop scenes are decided
};

/// The preset names, in the order of the table above.
std::vector<std::string> preset_names();

/// A validated sequence of `frames` frames (1 .. kMaxPresetFrames). Throws std::invalid_argument for
/// an unknown name (the message lists the known ones), frames out of range, or invalid settings
/// (e.g. the camera).
SequenceSpec make_preset(const std::string& name, int frames, std::uint64_t seed, const PresetSettings& settings = {});

}  // namespace sim
}  // namespace cge
