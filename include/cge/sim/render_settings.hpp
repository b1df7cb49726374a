#pragma once
// Settings of the synthetic RGB-D renderer: lighting and the depth-sensor model (docs/SIMULATION.md,
// "Realism"). Every field has its unit and default; validate_render_settings says what is allowed.

#include <string>

#include <Eigen/Core>

namespace cge {
namespace sim {

/// Lambert shading with one directional light plus an ambient term; no shadows.
struct LightingSettings {
  Eigen::Vector3d key_towards_light_world{0.35, -0.45, 1.0};  ///< direction to the light (normalised on use)
  double key_strength = 0.5;                                  ///< diffuse weight of the key light, >= 0
  double ambient = 0.55;                                      ///< light on every surface, >= 0
};

/// The depth-sensor model. Applied to the exact depth z (metres, along the optical axis) in order:
/// out of range -> 0; discontinuity -> 0; grazing incidence -> 0; random dropout -> 0; otherwise
/// z + sigma(z) * g with g about N(0, 1) (see noise_enabled), quantised to the camera's depth units.
struct DepthSensorSettings {
  /// Add range-dependent noise: sigma(z) = noise_base_m + noise_quadratic_per_m * (z - noise_reference_m)^2,
  /// the axial noise model of Kinect v1 fitted by Nguyen, Izadi and Lovell (3DIMPVT 2012) for the
  /// defaults. g is approximately standard normal: the sum of the four bytes of a 32-bit hash of
  /// (seed, frame, pixel), centred and scaled (unit variance, tails cut at 3.46 sigma). Off: the
  /// depth is exact up to quantisation.
  bool noise_enabled = true;
  double noise_base_m = 0.0012;           ///< sigma at noise_reference_m, metres, >= 0
  double noise_quadratic_per_m = 0.0019;  ///< growth of sigma with range, 1/metre, >= 0
  double noise_reference_m = 0.4;         ///< range of the smallest sigma, metres, >= 0
  double min_range_m = 0.4;               ///< nearer surfaces give no depth (the sensor's blind zone), metres
  double max_range_m = 4.5;               ///< farther surfaces give no depth, metres (> min_range_m)
  /// A pixel whose exact depth differs from one of its 4 neighbours' by more than this gets no depth
  /// (both sides of an object's silhouette lose a pixel, as structured-light sensors do). Metres, > 0;
  /// infinity switches the rule off.
  double discontinuity_jump_m = 0.08;
  /// Surfaces seen at more than this angle between the ray and the normal give no depth. Degrees,
  /// in (0, 90]; 90 switches the rule off.
  double max_incidence_deg = 82;
  double dropout_probability = 0.002;  ///< further pixels dropped at random, in [0, 1] (resolution 2^-32)
};

struct RenderSettings {
  LightingSettings lighting;
  DepthSensorSettings depth;
  double near_plane_m = 0.02;  ///< surfaces nearer than this (z) are not rendered at all, metres, > 0
};

/// Throws std::invalid_argument naming the field for a value outside its documented range.
void validate_render_settings(const RenderSettings& settings);

}  // namespace sim
}  // namespace cge
