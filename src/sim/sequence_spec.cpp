#include "cge/sim/sequence_spec.hpp"

#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include "cge/segmentation/coco_classes.hpp"

namespace cge {
namespace sim {
namespace {

// Largest |(R^T R - I)_ij| accepted for the rotation of a camera pose.
constexpr double kRotationTolerance = 1e-6;
// Largest image side accepted, pixels (far beyond any RGB-D sensor; keeps buffers sane).
constexpr int kMaxImageSidePx = 16384;
// Primitives of one frame are indexed with 16 bits; one value marks "nothing hit".
constexpr std::size_t kMaxFramePrimitives = 65534;

template <typename T>
std::string str(const T& value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

void require_positive(double value, const std::string& name) {
  if (!std::isfinite(value) || !(value > 0)) fail(name + " must be finite and > 0 (got " + str(value) + ")");
}

void require_non_negative(double value, const std::string& name) {
  if (!std::isfinite(value) || value < 0) fail(name + " must be finite and >= 0 (got " + str(value) + ")");
}

}  // namespace

void validate_render_settings(const RenderSettings& s) {
  const std::string p = "RenderSettings.";
  if (!s.lighting.key_towards_light_world.allFinite() || !(s.lighting.key_towards_light_world.norm() > 0)) {
    fail(p + "lighting.key_towards_light_world must be finite and non-zero");
  }
  require_non_negative(s.lighting.key_strength, p + "lighting.key_strength");
  require_non_negative(s.lighting.ambient, p + "lighting.ambient");
  const DepthSensorSettings& d = s.depth;
  require_non_negative(d.noise_base_m, p + "depth.noise_base_m");
  require_non_negative(d.noise_quadratic_per_m, p + "depth.noise_quadratic_per_m");
  require_non_negative(d.noise_reference_m, p + "depth.noise_reference_m");
  require_non_negative(d.min_range_m, p + "depth.min_range_m");
  require_positive(d.max_range_m, p + "depth.max_range_m");
  if (!(d.max_range_m > d.min_range_m)) {
    fail(p + "depth.max_range_m (" + str(d.max_range_m) + ") must be > depth.min_range_m (" + str(d.min_range_m) + ")");
  }
  if (std::isnan(d.discontinuity_jump_m) || !(d.discontinuity_jump_m > 0)) {
    fail(p + "depth.discontinuity_jump_m must be > 0 (infinity: off) (got " + str(d.discontinuity_jump_m) + ")");
  }
  if (!std::isfinite(d.max_incidence_deg) || !(d.max_incidence_deg > 0) || d.max_incidence_deg > 90) {
    fail(p + "depth.max_incidence_deg must be in (0, 90] (got " + str(d.max_incidence_deg) + ")");
  }
  if (!std::isfinite(d.dropout_probability) || d.dropout_probability < 0 || d.dropout_probability > 1) {
    fail(p + "depth.dropout_probability must be in [0, 1] (got " + str(d.dropout_probability) + ")");
  }
  require_positive(s.near_plane_m, p + "near_plane_m");
}

void validate_camera(const PinholeCamera& c, const std::string& where) {
  require_positive(c.fx_px, where + ".fx_px");
  require_positive(c.fy_px, where + ".fy_px");
  if (!std::isfinite(c.cx_px)) fail(where + ".cx_px must be finite (got " + str(c.cx_px) + ")");
  if (!std::isfinite(c.cy_px)) fail(where + ".cy_px must be finite (got " + str(c.cy_px) + ")");
  if (c.width_px < 1 || c.width_px > kMaxImageSidePx) {
    fail(where + ".width_px must be in 1 .. " + str(kMaxImageSidePx) + " (got " + str(c.width_px) + ")");
  }
  if (c.height_px < 1 || c.height_px > kMaxImageSidePx) {
    fail(where + ".height_px must be in 1 .. " + str(kMaxImageSidePx) + " (got " + str(c.height_px) + ")");
  }
  require_positive(c.depth_units_per_metre, where + ".depth_units_per_metre");
}

void validate_sequence_spec(const SequenceSpec& spec) {
  const std::string p = "SequenceSpec";
  validate_camera(spec.camera, p + ".camera");
  require_positive(spec.frame_rate_hz, p + ".frame_rate_hz");
  if (!std::isfinite(spec.start_timestamp_s)) fail(p + ".start_timestamp_s must be finite");
  validate_render_settings(spec.render);

  if (spec.T_world_camera.empty()) fail(p + ".T_world_camera is empty: a sequence needs at least one frame");
  if (spec.T_world_camera.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    fail(p + ".T_world_camera has too many frames");
  }
  for (std::size_t i = 0; i < spec.T_world_camera.size(); ++i) {
    const Eigen::Isometry3d& T = spec.T_world_camera[i];
    const Eigen::Matrix3d R = T.linear();
    const bool rotation_ok =
        R.allFinite() &&
        (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= kRotationTolerance &&
        R.determinant() > 0;
    if (!T.translation().allFinite() || !rotation_ok) {
      fail(p + ".T_world_camera[" + str(i) + "] is not a finite rigid motion (rotation must be orthonormal)");
    }
  }

  std::set<std::uint16_t> ids;
  for (std::size_t i = 0; i < spec.instances.size(); ++i) {
    const InstanceInfo& info = spec.instances[i];
    const std::string where = p + ".instances[" + str(i) + "]";
    if (info.id == 0) fail(where + ".id must be >= 1 (0 is the background)");
    if (!ids.insert(info.id).second) fail(where + ".id " + str(info.id) + " appears twice");
    if (info.class_id < 0 || info.class_id >= kCocoClassCount) {
      fail(where + ".class_id must be a COCO id 0 .. " + str(kCocoClassCount - 1) + " (got " + str(info.class_id) +
           ")");
    }
  }

  for (std::size_t i = 0; i < spec.static_primitives.size(); ++i) {
    const Primitive& prim = spec.static_primitives[i];
    const std::string where = p + ".static_primitives[" + str(i) + "]";
    validate_primitive(prim, where);
    if (prim.instance_id != 0 && ids.count(prim.instance_id) == 0) {
      fail(where + ".instance_id " + str(prim.instance_id) + " is not in SequenceSpec.instances");
    }
  }
  for (std::size_t i = 0; i < spec.people.size(); ++i) {
    const Person& person = spec.people[i];
    const std::string where = p + ".people[" + str(i) + "]";
    validate_person(person, where);
    if (ids.count(person.instance_id) == 0) {
      fail(where + ".instance_id " + str(person.instance_id) + " is not in SequenceSpec.instances");
    }
  }
  const std::size_t most = spec.static_primitives.size() + spec.people.size() * kMaxPrimitivesPerPerson;
  if (most > kMaxFramePrimitives) {
    fail(p + ": up to " + str(most) + " primitives in one frame, more than the " + str(kMaxFramePrimitives) +
         " the renderer indexes");
  }

  const int frames = static_cast<int>(spec.T_world_camera.size());
  for (std::size_t i = 0; i < spec.loops.size(); ++i) {
    const LoopPair& loop = spec.loops[i];
    if (loop.match_frame < 0 || loop.query_frame >= frames || !(loop.match_frame < loop.query_frame)) {
      fail(p + ".loops[" + str(i) + "] (query " + str(loop.query_frame) + ", match " + str(loop.match_frame) +
           ") must satisfy 0 <= match < query < " + str(frames));
    }
  }
}

}  // namespace sim
}  // namespace cge
