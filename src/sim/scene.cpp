#include "cge/sim/scene.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cge {
namespace sim {
namespace {

// Largest |(R^T R - I)_ij| accepted for a rotation.
constexpr double kRotationTolerance = 1e-6;

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

bool is_rotation(const Eigen::Matrix3d& R) {
  return R.allFinite() &&
         ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= kRotationTolerance) &&
         R.determinant() > 0;
}

Eigen::Isometry3d yawed(const Eigen::Vector3d& centre_m, double yaw_rad) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = centre_m;
  return T;
}

/// A right-handed frame whose z axis is `z` and whose x axis is the part of `x_hint` orthogonal to
/// it (or any perpendicular when the hint is parallel).
Eigen::Matrix3d frame_from_z(const Eigen::Vector3d& z, const Eigen::Vector3d& x_hint) {
  const Eigen::Vector3d ez = z.normalized();
  Eigen::Vector3d ex = x_hint - x_hint.dot(ez) * ez;
  if (ex.norm() < 1e-9 * (1 + x_hint.norm())) ex = ez.unitOrthogonal();
  ex.normalize();
  Eigen::Matrix3d R;
  R.col(0) = ex;
  R.col(1) = ez.cross(ex);
  R.col(2) = ez;
  return R;
}

}  // namespace

void validate_primitive(const Primitive& p, const std::string& where) {
  const bool quad = p.shape == Shape::quad;
  const bool capsule = p.shape == Shape::capsule;
  for (int k = 0; k < 3; ++k) {
    const double s = p.size_m[k];
    const bool unused = (quad && k == 2) || (capsule && k == 1);
    if (!std::isfinite(s) || (!unused && !(s > 0))) {
      std::ostringstream msg;
      msg << "size_m[" << k << "] must be finite and > 0 (got " << s << ")";
      fail(where, msg.str());
    }
  }
  if (!p.T_world_local.translation().allFinite()) fail(where, "T_world_local has a non-finite translation");
  if (!is_rotation(p.T_world_local.linear())) fail(where, "T_world_local's rotation is not orthonormal");
  if (!std::isfinite(p.material.scale_m) || !(p.material.scale_m > 0)) {
    fail(where, "material.scale_m must be finite and > 0 (got " + std::to_string(p.material.scale_m) + ")");
  }
  if (!p.material.colour_a.allFinite() || !p.material.colour_b.allFinite()) {
    fail(where, "material colours must be finite");
  }
  if (p.first_frame < 0) fail(where, "first_frame must be >= 0 (got " + std::to_string(p.first_frame) + ")");
  if (p.last_frame < p.first_frame) {
    fail(where, "last_frame must be >= first_frame (got " + std::to_string(p.last_frame) + " < " +
                    std::to_string(p.first_frame) + ")");
  }
}

Primitive make_box(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_size_m, double yaw_rad,
                   const Material& material, std::uint16_t instance_id) {
  Primitive p;
  p.shape = Shape::box;
  p.T_world_local = yawed(centre_m, yaw_rad);
  p.size_m = half_size_m;
  p.material = material;
  p.instance_id = instance_id;
  return p;
}

Primitive make_quad(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& normal, const Eigen::Vector3d& along_u,
                    double half_u_m, double half_v_m, const Material& material, std::uint16_t instance_id) {
  Primitive p;
  p.shape = Shape::quad;
  p.T_world_local = Eigen::Isometry3d::Identity();
  p.T_world_local.linear() = frame_from_z(normal, along_u);
  p.T_world_local.translation() = centre_m;
  p.size_m = Eigen::Vector3d(half_u_m, half_v_m, 0);
  p.material = material;
  p.instance_id = instance_id;
  return p;
}

Primitive make_ellipsoid(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& radii_m, double yaw_rad,
                         const Material& material, std::uint16_t instance_id) {
  Primitive p;
  p.shape = Shape::ellipsoid;
  p.T_world_local = yawed(centre_m, yaw_rad);
  p.size_m = radii_m;
  p.material = material;
  p.instance_id = instance_id;
  return p;
}

Primitive make_capsule(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m, double radius_m,
                       const Material& material, std::uint16_t instance_id, const Eigen::Vector3d& side) {
  const Eigen::Vector3d axis = b_m - a_m;
  if (!(axis.norm() > 0)) throw std::invalid_argument("make_capsule: the two end points coincide");
  Primitive p;
  p.shape = Shape::capsule;
  p.T_world_local = Eigen::Isometry3d::Identity();
  p.T_world_local.linear() = frame_from_z(axis, side);
  p.T_world_local.translation() = 0.5 * (a_m + b_m);
  p.size_m = Eigen::Vector3d(radius_m, radius_m, 0.5 * axis.norm());
  p.material = material;
  p.instance_id = instance_id;
  return p;
}

}  // namespace sim
}  // namespace cge
