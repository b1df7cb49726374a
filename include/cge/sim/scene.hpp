#pragma once
// The geometry of a synthetic scene: primitives (quads, boxes, ellipsoids, capsules) with
// procedural materials, each belonging to an object instance or to the background.
//
// Units: metres. World frame z up (cge/sim/sequence.hpp). Every primitive has its own local frame
// T_world_local; its size is given in that frame (see Shape). Textures are functions of the
// local surface coordinates in metres, so a pattern stays glued to its surface whatever the camera
// does (features track like real ones), and people's clothes move with their limbs.

#include <cstdint>
#include <limits>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cge {
namespace sim {

/// What a primitive is, and how Primitive::size_m is read.
enum class Shape : std::uint8_t {
  quad,       ///< rectangle in the local xy-plane, half sizes size_m.x(), size_m.y(); seen from both sides
  box,        ///< cuboid with half sizes size_m along local x, y, z
  ellipsoid,  ///< ellipsoid with radii size_m along local x, y, z
  capsule,    ///< segment from (0,0,-size_m.z()) to (0,0,+size_m.z()) swept by a sphere of radius size_m.x()
};

/// Procedural surface patterns; all made of integer-hashed cells, so they are deterministic and
/// rich in corners (what FAST/ORB detects). Cell sizes come from Material::scale_m.
enum class Pattern : std::uint8_t {
  plain,   ///< colour_a with a faint mottling (skin, painted metal)
  noise,   ///< two-octave value noise between colour_a and colour_b (plaster, fabric, cork)
  bricks,  ///< running-bond bricks of length scale_m (height 0.4 scale_m), mortar colour_b
  planks,  ///< wood planks of width scale_m with grain and staggered joints (colour_b)
  tiles,   ///< square tiles of side scale_m with grout colour_b (floors, ceilings, keyboards)
  blocks,  ///< per cell of side scale_m a random rectangle, disc or stripes in strong colours (posters)
  checks,  ///< tartan-like crossing stripes of width scale_m / 2 (shirts, upholstery)
  spines,  ///< book spines of width about scale_m with title bands, along local u
  screen,  ///< a desktop on screen: windows with title bars and lines of text-like blocks
  leaves,  ///< overlapping leaf-sized discs of greens on colour_b (foliage)
};

/// Surface appearance. Colours are RGB in [0, 1] (converted to the frame's BGR at output).
struct Material {
  Pattern pattern = Pattern::noise;
  Eigen::Vector3f colour_a{0.6f, 0.6f, 0.6f};  ///< main colour
  Eigen::Vector3f colour_b{0.3f, 0.3f, 0.3f};  ///< second colour (mortar, grout, background, ...)
  float scale_m = 0.1f;                        ///< cell size of the pattern, metres (> 0)
  std::uint32_t salt = 0;                      ///< varies the random parts of the pattern
};

/// One solid of the scene.
struct Primitive {
  Shape shape = Shape::box;
  Eigen::Isometry3d T_world_local = Eigen::Isometry3d::Identity();  ///< pose of the local frame
  Eigen::Vector3d size_m{0.5, 0.5, 0.5};  ///< half sizes or radii in the local frame (see Shape), > 0
  Material material;
  std::uint16_t instance_id = 0;  ///< InstanceInfo::id, or 0 for the background (walls, shelves, ...)
  int first_frame = 0;            ///< the primitive exists from this frame on (objects added mid-sequence)
  /// ... up to and including this frame (objects taken away mid-sequence); the default: to the end.
  int last_frame = std::numeric_limits<int>::max();
};

/// Throws std::invalid_argument naming `where` (e.g. "static_primitives[3]") when a size, pose or
/// scale is not finite and positive, the rotation is not orthonormal, first_frame < 0 or
/// last_frame < first_frame.
void validate_primitive(const Primitive& primitive, const std::string& where);

// ---- construction helpers ----------------------------------------------------------------------

/// A box centred at centre_m, rotated by yaw_rad about the world z axis.
Primitive make_box(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_size_m, double yaw_rad,
                   const Material& material, std::uint16_t instance_id = 0);

/// A quad centred at centre_m whose local x axis is along_u and whose normal is `normal`
/// (orthogonalised against each other); half sizes half_u_m along u and half_v_m along normal x u.
Primitive make_quad(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& normal, const Eigen::Vector3d& along_u,
                    double half_u_m, double half_v_m, const Material& material, std::uint16_t instance_id = 0);

/// An ellipsoid centred at centre_m with radii along the world axes after a yaw about world z.
Primitive make_ellipsoid(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& radii_m, double yaw_rad,
                         const Material& material, std::uint16_t instance_id = 0);

/// A capsule from a_m to b_m (distinct points) of radius radius_m. Its local x axis is the part of
/// `side` orthogonal to the segment (any perpendicular when `side` is parallel to it), so that a
/// limb's texture turns with the limb.
Primitive make_capsule(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m, double radius_m,
                       const Material& material, std::uint16_t instance_id = 0,
                       const Eigen::Vector3d& side = Eigen::Vector3d::UnitX());

}  // namespace sim
}  // namespace cge
