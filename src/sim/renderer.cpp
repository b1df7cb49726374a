#include "cge/sim/renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "cge/core/splitmix64.hpp"
#include "texture.hpp"

namespace cge {
namespace sim {
namespace {

using detail::PreparedPrimitive;
using detail::Rgb;

constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr std::int32_t kNoPrimitive = -1;  // in the primitive-index buffer
constexpr double kPi = 3.14159265358979323846;

// ---- per-pixel random numbers: counter-based, a function of (seed, frame, pixel) only ------------

/// A 32-bit hash of a pixel index under a frame key (multiply-xorshift).
std::uint32_t pixel_hash(std::uint32_t pixel, std::uint32_t key) {
  std::uint32_t h = (pixel ^ key) * 0x9e3779b1u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

/// Approximately standard normal from 32 random bits: the sum of the four bytes, centred and
/// scaled to unit variance (Irwin-Hall with four terms; tails cut at 3.46 sigma). Pure arithmetic,
/// so the depth pass vectorises.
inline float gaussian_from_bits(std::uint32_t h) {
  // Four bytes: mean 4 * 127.5, variance 4 * (256^2 - 1) / 12.
  constexpr float kMean = 510.0f;
  constexpr float kInvSigma = 0.0067658f;  // 1 / sqrt(21845)
  const std::uint32_t sum = (h & 0xFFu) + ((h >> 8) & 0xFFu) + ((h >> 16) & 0xFFu) + (h >> 24);
  return (static_cast<float>(static_cast<std::int32_t>(sum)) - kMean) * kInvSigma;
}

// ---- preparation: the camera ray in each primitive's local frame, and its screen rectangle --------

/// Half sizes of the primitive's local bounding box.
Eigen::Vector3d bounding_half_size(const Primitive& p) {
  switch (p.shape) {
    case Shape::quad:
      return Eigen::Vector3d(p.size_m.x(), p.size_m.y(), 0);
    case Shape::capsule:
      return Eigen::Vector3d(p.size_m.x(), p.size_m.x(), p.size_m.z() + p.size_m.x());
    case Shape::box:
    case Shape::ellipsoid:
      break;
  }
  return p.size_m;
}

struct Point2 {
  double x, y;
};

double turn(const Point2& o, const Point2& a, const Point2& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/// Convex hull of n >= 1 points (Andrew's monotone chain), counter-clockwise, into `hull`
/// (capacity 2n); returns its size (1 or 2 for degenerate input).
std::size_t convex_hull(Point2* pts, std::size_t n, Point2* hull) {
  std::sort(pts, pts + n, [](const Point2& a, const Point2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  if (n < 3) {
    std::copy(pts, pts + n, hull);
    return n;
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && turn(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = n - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && turn(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  return k - 1;
}

/// Columns [begin, end) of row v whose pixel centres may lie in the convex polygon: the polygon's
/// extent over the band v +- 1 (vertices inside it, edges crossing its borders), widened by a pixel,
/// so that rounding in the float ray tests never loses a pixel.
void row_span(const Point2* hull, std::size_t n, double v, int width, std::int32_t& begin, std::int32_t& end) {
  const double lo = v - 1, hi = v + 1;
  double u_min = std::numeric_limits<double>::infinity();
  double u_max = -u_min;
  for (std::size_t i = 0; i < n; ++i) {
    const Point2& a = hull[i];
    const Point2& b = hull[(i + 1) % n];
    if (a.y >= lo && a.y <= hi) {
      u_min = std::min(u_min, a.x);
      u_max = std::max(u_max, a.x);
    }
    for (const double line : {lo, hi}) {
      if ((a.y - line) * (b.y - line) < 0) {
        const double x = a.x + (line - a.y) / (b.y - a.y) * (b.x - a.x);
        u_min = std::min(u_min, x);
        u_max = std::max(u_max, x);
      }
    }
  }
  begin = end = 0;
  if (!(u_min <= u_max)) return;
  const double first = std::max(0.0, std::ceil(u_min - 1));
  const double last = std::min(static_cast<double>(width - 1), std::floor(u_max + 1));
  if (first <= last) {
    begin = static_cast<std::int32_t>(first);
    end = static_cast<std::int32_t>(last) + 1;
  }
}

/// Fills `out` (and its row spans) for one primitive; false when it cannot be seen.
bool prepare(const Primitive& prim, const Eigen::Isometry3d& T_camera_world, const PinholeCamera& cam,
             const LightingSettings& lighting, double near_m, PreparedPrimitive& out,
             std::vector<std::int32_t>& spans) {
  const Eigen::Isometry3d T_camera_local = T_camera_world * prim.T_world_local;
  const Eigen::Vector3d h = bounding_half_size(prim);

  // Screen outline: the convex hull of the bounding box's corners in front of the near plane and of
  // the points where its edges cross that plane (the projection of the box clipped at the plane).
  std::array<Eigen::Vector3d, 8> corner;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
    corner[static_cast<std::size_t>(i)] = T_camera_local * c;
  }
  std::array<Point2, 20> points;  // 8 corners + 12 edges at most
  std::size_t count = 0;
  auto project = [&](const Eigen::Vector3d& q) {
    points[count++] = Point2{cam.cx_px + cam.fx_px * q.x() / q.z(), cam.cy_px + cam.fy_px * q.y() / q.z()};
  };
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d& a = corner[static_cast<std::size_t>(i)];
    if (a.z() >= near_m) project(a);
    for (int bit = 1; bit < 8; bit <<= 1) {
      if (i & bit) continue;
      const Eigen::Vector3d& b = corner[static_cast<std::size_t>(i | bit)];
      if ((a.z() >= near_m) != (b.z() >= near_m)) {
        const double f = (near_m - a.z()) / (b.z() - a.z());
        Eigen::Vector3d q = a + f * (b - a);
        q.z() = near_m;
        project(q);
      }
    }
  }
  if (count == 0) return false;
  std::array<Point2, 40> hull;
  const std::size_t hull_size = convex_hull(points.data(), count, hull.data());
  double v_min = hull[0].y, v_max = hull[0].y;
  for (std::size_t i = 1; i < hull_size; ++i) {
    v_min = std::min(v_min, hull[i].y);
    v_max = std::max(v_max, hull[i].y);
  }
  const double first_row = std::max(0.0, std::ceil(v_min - 1));
  const double last_row = std::min(static_cast<double>(cam.height_px - 1), std::floor(v_max + 1));
  if (!(first_row <= last_row)) return false;
  out.v_begin = static_cast<int>(first_row);
  out.v_end = static_cast<int>(last_row) + 1;
  out.span_offset = spans.size();
  bool any = false;
  for (int v = out.v_begin; v < out.v_end; ++v) {
    std::int32_t begin, end;
    row_span(hull.data(), hull_size, v, cam.width_px, begin, end);
    spans.push_back(begin);
    spans.push_back(end);
    any = any || begin < end;
  }
  if (!any) {
    spans.resize(out.span_offset);
    return false;
  }

  // Ray of pixel (u, v) in local coordinates: origin + z * (dir_0 + u dir_u + v dir_v), where z is
  // the depth along the camera's optical axis (the camera-frame direction has z = 1).
  const Eigen::Matrix3d R_local_camera = T_camera_local.linear().transpose();
  Eigen::Vector3d origin = -(R_local_camera * T_camera_local.translation());
  Eigen::Vector3d dir_u = R_local_camera.col(0) / cam.fx_px;
  Eigen::Vector3d dir_v = R_local_camera.col(1) / cam.fy_px;
  Eigen::Vector3d dir_0 = R_local_camera.col(2) - cam.cx_px * dir_u - cam.cy_px * dir_v;
  Eigen::Vector3d size = prim.size_m;
  if (prim.shape == Shape::ellipsoid) {  // work in the frame where the ellipsoid is the unit sphere
    const Eigen::Vector3d inv = prim.size_m.cwiseInverse();
    origin = origin.cwiseProduct(inv);
    dir_u = dir_u.cwiseProduct(inv);
    dir_v = dir_v.cwiseProduct(inv);
    dir_0 = dir_0.cwiseProduct(inv);
  }
  const Eigen::Vector3d light = prim.T_world_local.linear().transpose() * lighting.key_towards_light_world.normalized();
  for (int k = 0; k < 3; ++k) {
    out.origin[k] = static_cast<float>(origin[k]);
    out.dir_u[k] = static_cast<float>(dir_u[k]);
    out.dir_v[k] = static_cast<float>(dir_v[k]);
    out.dir_0[k] = static_cast<float>(dir_0[k]);
    out.size[k] = static_cast<float>(size[k]);
    out.light[k] = static_cast<float>(light[k]);
    out.metric[k] = prim.shape == Shape::ellipsoid ? static_cast<float>(prim.size_m[k]) : 1.0f;
    out.inv_size[k] = size[k] > 0 ? static_cast<float>(1.0 / size[k]) : 0.0f;
    for (int side = 0; side < 2; ++side) {  // flat faces: face 2k + side has normal (2 side - 1) e_k
      const double lambert = (side == 1 ? 1.0 : -1.0) * light[k];
      out.face_light[2 * k + side] =
          static_cast<float>(lighting.ambient + lighting.key_strength * std::max(lambert, 0.0));
    }
  }
  out.texture_scale = 1.0f / prim.material.scale_m;
  out.shape = prim.shape;
  out.instance_id = prim.instance_id;
  out.material = &prim.material;
  return true;
}

// ---- intersection: depth z of the first hit at or beyond the near plane, or infinity -------------
// Branch-free (selects instead of early returns) so that the raster loop vectorises.

inline float select(bool condition, float a, float b) { return condition ? a : b; }

struct QuadHit {
  float ox, oy, oz, hx, hy, near_m;
  float operator()(float dx, float dy, float dz) const {
    const float z = -oz / dz;  // dz == 0 gives +-inf or nan: rejected below
    const float px = ox + z * dx;
    const float py = oy + z * dy;
    const bool hit = (z >= near_m) & (std::abs(px) <= hx) & (std::abs(py) <= hy);
    return select(hit, z, kInfinity);
  }
};

struct BoxHit {
  float ox, oy, oz, hx, hy, hz, near_m;
  float operator()(float dx, float dy, float dz) const {
    const float ix = 1.0f / dx, iy = 1.0f / dy, iz = 1.0f / dz;
    const float ax = (-hx - ox) * ix, bx = (hx - ox) * ix;
    const float ay = (-hy - oy) * iy, by = (hy - oy) * iy;
    const float az = (-hz - oz) * iz, bz = (hz - oz) * iz;
    const float t_near = std::max(std::max(std::min(ax, bx), std::min(ay, by)), std::min(az, bz));
    const float t_far = std::min(std::min(std::max(ax, bx), std::max(ay, by)), std::max(az, bz));
    const bool hit = (t_near <= t_far) & (t_far >= near_m);
    // From inside a box (t_near behind the near plane), its far side.
    return select(hit, select(t_near >= near_m, t_near, t_far), kInfinity);
  }
};

struct SphereHit {              // the unit sphere (an ellipsoid in its scaled frame)
  float ox, oy, oz, c, near_m;  // c = |o|^2 - 1
  float operator()(float dx, float dy, float dz) const {
    const float a = dx * dx + dy * dy + dz * dz;
    const float b = ox * dx + oy * dy + oz * dz;
    const float disc = b * b - a * c;
    const float z = (-b - std::sqrt(std::max(disc, 0.0f))) / a;
    return select((disc >= 0) & (z >= near_m), z, kInfinity);
  }
};

struct CapsuleHit {  // axis along local z from -half_length to +half_length
  float ox, oy, oz, r, half_length, near_m;
  float operator()(float dx, float dy, float dz) const {
    // The infinite cylinder; a ray that misses it misses the caps too.
    const float a = dx * dx + dy * dy;
    const float b = ox * dx + oy * dy;
    const float c = ox * ox + oy * oy - r * r;
    const float disc = b * b - a * c;
    const float z_side = (-b - std::sqrt(std::max(disc, 0.0f))) / a;
    // Where the ray enters the cylinder (its start when parallel to the axis).
    const float pz = select(a > 0, oz + z_side * dz, oz);
    const bool on_side = (a > 0) & (std::abs(pz) <= half_length);
    // Entering beyond one end: the first hit, if any, is on that end's cap.
    const float cz = oz - select(pz > 0, half_length, -half_length);
    const float a2 = a + dz * dz;
    const float b2 = b + cz * dz;
    const float c2 = c + cz * cz;
    const float disc2 = b2 * b2 - a2 * c2;
    const float z_cap = (-b2 - std::sqrt(std::max(disc2, 0.0f))) / a2;
    const float z = select(on_side, z_side, z_cap);
    const bool hit = (disc >= 0) & (select(on_side, 1.0f, disc2) >= 0) & (z >= near_m);
    return select(hit, z, kInfinity);
  }
};

/// Intersects every ray of the primitive's row spans, keeping the nearest hit per pixel. The
/// intersections of a span go to `scratch` first: that loop has no stores into the buffers and no
/// branches, so it vectorises; the merge into the z-buffer follows.
template <typename Hit>
void raster(const PreparedPrimitive& p, std::int32_t index, const Hit& hit, const std::int32_t* spans, float* scratch,
            cv::Mat& depth, cv::Mat& ids) {
  const float dux = p.dir_u[0], duy = p.dir_u[1], duz = p.dir_u[2];
  for (int v = p.v_begin; v < p.v_end; ++v) {
    const std::int32_t* span = spans + p.span_offset + 2 * (v - p.v_begin);
    const int begin = span[0];
    const int n = span[1] - begin;
    const float fv = static_cast<float>(v);
    const float rx = p.dir_0[0] + fv * p.dir_v[0] + static_cast<float>(begin) * dux;
    const float ry = p.dir_0[1] + fv * p.dir_v[1] + static_cast<float>(begin) * duy;
    const float rz = p.dir_0[2] + fv * p.dir_v[2] + static_cast<float>(begin) * duz;
    for (int i = 0; i < n; ++i) {
      const float fi = static_cast<float>(i);
      scratch[i] = hit(rx + fi * dux, ry + fi * duy, rz + fi * duz);
    }
    float* z_row = depth.ptr<float>(v) + begin;
    std::int32_t* id_row = ids.ptr<std::int32_t>(v) + begin;
    for (int i = 0; i < n; ++i) {  // unconditional stores and integer masks: it vectorises too
      const float old_z = z_row[i];
      const std::int32_t nearer = scratch[i] < old_z ? 1 : 0;
      z_row[i] = std::min(scratch[i], old_z);
      id_row[i] += (index - id_row[i]) * nearer;
    }
  }
}

void raster_primitive(const PreparedPrimitive& p, std::int32_t index, float near_m, const std::int32_t* spans,
                      float* scratch, cv::Mat& depth, cv::Mat& ids) {
  const float* o = p.origin;
  switch (p.shape) {
    case Shape::quad:
      raster(p, index, QuadHit{o[0], o[1], o[2], p.size[0], p.size[1], near_m}, spans, scratch, depth, ids);
      break;
    case Shape::box:
      raster(p, index, BoxHit{o[0], o[1], o[2], p.size[0], p.size[1], p.size[2], near_m}, spans, scratch, depth, ids);
      break;
    case Shape::ellipsoid:
      raster(p, index, SphereHit{o[0], o[1], o[2], o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 1.0f, near_m}, spans,
             scratch, depth, ids);
      break;
    case Shape::capsule:
      raster(p, index, CapsuleHit{o[0], o[1], o[2], p.size[0], p.size[2], near_m}, spans, scratch, depth, ids);
      break;
  }
}

// ---- shading -------------------------------------------------------------------------------------

/// Per-pixel outputs of the surface pass over one run of pixels of the same primitive.
struct RunSamples {
  float* x;  // texture coordinates in pattern cells
  float* y;
  float* light;              // ambient + diffuse
  std::uint8_t* measurable;  // 1 where the incidence angle allows a depth measurement
};

/// Shading constants of a frame.
struct ShadeConstants {
  float ambient, key, min_cos2_incidence;
};

/// Texture coordinates from the two local axes most orthogonal to the normal.
inline void planar_uv(float px, float py, float pz, float nx, float ny, float nz, float& u, float& v) {
  const float ax = std::abs(nx), ay = std::abs(ny), az = std::abs(nz);
  const bool x_major = ax >= ay && ax >= az;
  const bool y_major = !x_major && ay >= az;
  u = x_major ? py : px;
  v = (x_major || y_major) ? pz : py;
}

/// The surface pass over pixels u0 .. u0 + n - 1 of row v, all on primitive p: texture
/// coordinates, light and measurability per pixel. One instantiation per shape keeps the loop free
/// of per-pixel dispatch and the primitive's constants in registers.
template <Shape kShape>
void sample_run(const PreparedPrimitive& p, const float* z, int u0, int n, float fv, const ShadeConstants& k,
                RunSamples out) {
  const float ox = p.origin[0], oy = p.origin[1], oz = p.origin[2];
  const float dux = p.dir_u[0], duy = p.dir_u[1], duz = p.dir_u[2];
  const float fu0 = static_cast<float>(u0);
  const float bx = p.dir_0[0] + fv * p.dir_v[0] + fu0 * dux;
  const float by = p.dir_0[1] + fv * p.dir_v[1] + fu0 * duy;
  const float bz = p.dir_0[2] + fv * p.dir_v[2] + fu0 * duz;
  const float scale = p.texture_scale;
  const float min_cos2 = k.min_cos2_incidence;
  if (kShape == Shape::quad) {
    // The camera sees one side of a quad (the one its centre is on): one light for the run.
    const float light = p.face_light[oz > 0 ? 5 : 4];
    for (int i = 0; i < n; ++i) {
      const float fi = static_cast<float>(i);
      const float dx = bx + fi * dux, dy = by + fi * duy, dz = bz + fi * duz;
      out.x[i] = (ox + z[i] * dx) * scale;
      out.y[i] = (oy + z[i] * dy) * scale;
      out.light[i] = light;
      out.measurable[i] = dz * dz >= min_cos2 * (dx * dx + dy * dy + dz * dz) ? 1 : 0;
    }
    return;
  }
  for (int i = 0; i < n; ++i) {
    const float fi = static_cast<float>(i);
    const float dx = bx + fi * dux, dy = by + fi * duy, dz = bz + fi * duz;
    const float qx = ox + z[i] * dx, qy = oy + z[i] * dy, qz = oz + z[i] * dz;
    const float len2 = dx * dx + dy * dy + dz * dz;
    if (kShape == Shape::box) {
      // The face hit: the axis where the point is relatively farthest out.
      const float rx = std::abs(qx) * p.inv_size[0], ry = std::abs(qy) * p.inv_size[1];
      const float rz = std::abs(qz) * p.inv_size[2];
      const int k_axis = (rx >= ry && rx >= rz) ? 0 : (ry >= rz ? 1 : 2);
      const float q_k = k_axis == 0 ? qx : (k_axis == 1 ? qy : qz);
      const float d_k = k_axis == 0 ? dx : (k_axis == 1 ? dy : dz);
      const int face = 2 * k_axis + (q_k > 0 ? 1 : 0);
      // Faces get different offsets so that they do not show the same pattern.
      constexpr float kFaceOffset = 3.7f;
      const float u = (k_axis == 0 ? qy : qx) + kFaceOffset * static_cast<float>(face);
      const float v = k_axis == 2 ? qy : qz;
      out.x[i] = u * scale;
      out.y[i] = v * scale;
      out.light[i] = p.face_light[face];
      out.measurable[i] = d_k * d_k >= min_cos2 * len2 ? 1 : 0;
    } else {
      float nx, ny, nz, mx, my, mz;        // normal; metric local point
      float dmx = dx, dmy = dy, dmz = dz;  // metric ray direction
      if (kShape == Shape::ellipsoid) {    // q lives in the unit-sphere frame
        nx = qx * p.inv_size[0];
        ny = qy * p.inv_size[1];
        nz = qz * p.inv_size[2];
        mx = qx * p.size[0];
        my = qy * p.size[1];
        mz = qz * p.size[2];
        dmx *= p.size[0];
        dmy *= p.size[1];
        dmz *= p.size[2];
      } else {  // capsule: from the nearest point of the axis segment
        const float hl = p.size[2];
        nx = qx;
        ny = qy;
        nz = qz - std::min(std::max(qz, -hl), hl);
        mx = qx;
        my = qy;
        mz = qz;
      }
      const float inv = 1.0f / std::sqrt(nx * nx + ny * ny + nz * nz);
      nx *= inv;
      ny *= inv;
      nz *= inv;
      const float lambert = nx * p.light[0] + ny * p.light[1] + nz * p.light[2];
      float u, v;
      planar_uv(mx, my, mz, nx, ny, nz, u, v);
      out.x[i] = u * scale;
      out.y[i] = v * scale;
      out.light[i] = k.ambient + k.key * std::max(lambert, 0.0f);
      const float dot = nx * dmx + ny * dmy + nz * dmz;
      out.measurable[i] = dot * dot >= min_cos2 * (dmx * dmx + dmy * dmy + dmz * dmz) ? 1 : 0;
    }
  }
}

void sample_run(const PreparedPrimitive& p, const float* z, int u0, int n, float fv, const ShadeConstants& k,
                RunSamples out) {
  switch (p.shape) {
    case Shape::quad:
      return sample_run<Shape::quad>(p, z, u0, n, fv, k, out);
    case Shape::box:
      return sample_run<Shape::box>(p, z, u0, n, fv, k, out);
    case Shape::ellipsoid:
      return sample_run<Shape::ellipsoid>(p, z, u0, n, fv, k, out);
    case Shape::capsule:
      return sample_run<Shape::capsule>(p, z, u0, n, fv, k, out);
  }
}

/// [0, 1] to 0 .. 255, rounded and clamped (colours are finite and small: no overflow).
std::uint8_t to_byte(float x) {
  const auto i = static_cast<std::int32_t>(x * 255.0f + 0.5f);  // truncation = rounding for x >= 0
  return static_cast<std::uint8_t>(i < 0 ? 0 : (i > 255 ? 255 : i));
}

}  // namespace

SequenceRenderer::SequenceRenderer(SequenceSpec spec) : spec_(std::move(spec)) { validate_sequence_spec(spec_); }

void SequenceRenderer::check_index(int index) const {
  if (index < 0 || index >= frame_count()) {
    throw std::invalid_argument("SequenceRenderer: frame index " + std::to_string(index) + " is not in 0 .. " +
                                std::to_string(frame_count() - 1));
  }
}

void SequenceRenderer::collect_primitives(int index, RenderWorkspace& ws) const {
  const double t = time_s(index);
  ws.people_primitives.clear();
  for (const Person& person : spec_.people) append_person_primitives(person, t, ws.people_primitives);
  ws.frame_primitives.clear();
  for (const Primitive& p : spec_.static_primitives) {
    if (p.first_frame <= index && index <= p.last_frame) ws.frame_primitives.push_back(&p);
  }
  for (const Primitive& p : ws.people_primitives) ws.frame_primitives.push_back(&p);
}

std::vector<Primitive> SequenceRenderer::primitives_at(int index) const {
  check_index(index);
  RenderWorkspace ws;
  collect_primitives(index, ws);
  std::vector<Primitive> out;
  out.reserve(ws.frame_primitives.size());
  for (const Primitive* p : ws.frame_primitives) out.push_back(*p);
  return out;
}

RenderedFrame SequenceRenderer::render(int index) const {
  RenderedFrame frame;
  RenderWorkspace ws;
  render_into(index, frame, ws);
  return frame;
}

void SequenceRenderer::render_into(int index, RenderedFrame& frame, RenderWorkspace& ws) const {
  check_index(index);
  const PinholeCamera& cam = spec_.camera;
  const RenderSettings& rs = spec_.render;
  const int width = cam.width_px;
  const int height = cam.height_px;

  frame.index = index;
  frame.timestamp_s = spec_.start_timestamp_s + time_s(index);
  frame.T_world_camera = spec_.T_world_camera[static_cast<std::size_t>(index)];
  frame.rgb.create(height, width, CV_8UC3);
  frame.depth.create(height, width, CV_16UC1);
  frame.instance_labels.create(height, width, CV_16UC1);
  ws.depth_exact_m.create(height, width, CV_32FC1);
  ws.primitive_index.create(height, width, CV_32SC1);
  for (int v = 0; v < height; ++v) {  // plain loops: no OpenCV call that might use threads
    std::fill_n(ws.depth_exact_m.ptr<float>(v), width, kInfinity);
    std::fill_n(ws.primitive_index.ptr<std::int32_t>(v), width, kNoPrimitive);
  }

  ws.row_x.resize(static_cast<std::size_t>(width));  // raster scratch (a span is at most a row)
  // Visibility: prepare and z-buffer every primitive present in this frame.
  collect_primitives(index, ws);
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  const float near_m = static_cast<float>(rs.near_plane_m);
  ws.prepared.clear();
  ws.spans.clear();
  for (const Primitive* prim : ws.frame_primitives) {
    PreparedPrimitive prepared;
    if (prepare(*prim, T_camera_world, cam, rs.lighting, rs.near_plane_m, prepared, ws.spans)) {
      ws.prepared.push_back(prepared);
    }
  }
  for (std::size_t i = 0; i < ws.prepared.size(); ++i) {
    raster_primitive(ws.prepared[i], static_cast<std::int32_t>(i), near_m, ws.spans.data(), ws.row_x.data(),
                     ws.depth_exact_m, ws.primitive_index);
  }

  shade(ws, frame);
  measure_depth(index, ws, frame);
}

void SequenceRenderer::shade(RenderWorkspace& ws, RenderedFrame& frame) const {
  // Per row, per run of pixels on the same primitive: surface samples, texture, colour, label.
  const int width = spec_.camera.width_px;
  const int height = spec_.camera.height_px;
  const DepthSensorSettings& ds = spec_.render.depth;
  ShadeConstants k;
  k.ambient = static_cast<float>(spec_.render.lighting.ambient);
  k.key = static_cast<float>(spec_.render.lighting.key_strength);
  // 90 degrees switches the rule off (cos 90 would be 6e-17, not 0).
  const float min_cos_incidence =
      ds.max_incidence_deg < 90 ? static_cast<float>(std::cos(ds.max_incidence_deg * kPi / 180.0)) : 0.0f;
  k.min_cos2_incidence = min_cos_incidence * min_cos_incidence;
  const std::uint8_t* noise_table = detail::noise_table();
  ws.measurable.create(height, width, CV_8UC1);
  const auto row_size = static_cast<std::size_t>(width);
  ws.row_x.resize(row_size);
  ws.row_y.resize(row_size);
  ws.row_light.resize(row_size);
  ws.row_colour.resize(3 * row_size);

  for (int v = 0; v < height; ++v) {
    const float* z_row = ws.depth_exact_m.ptr<float>(v);
    const std::int32_t* id_row = ws.primitive_index.ptr<std::int32_t>(v);
    std::uint8_t* bgr = frame.rgb.ptr<std::uint8_t>(v);
    std::uint16_t* label_row = frame.instance_labels.ptr<std::uint16_t>(v);
    std::uint8_t* measurable_row = ws.measurable.ptr<std::uint8_t>(v);
    const float fv = static_cast<float>(v);
    for (int u0 = 0; u0 < width;) {
      const std::int32_t pi = id_row[u0];
      int u1 = u0 + 1;
      while (u1 < width && id_row[u1] == pi) ++u1;
      const int n = u1 - u0;
      if (pi == kNoPrimitive) {
        std::fill(bgr + 3 * u0, bgr + 3 * u1, std::uint8_t{0});
        std::fill(label_row + u0, label_row + u1, std::uint16_t{0});
        std::fill(measurable_row + u0, measurable_row + u1, std::uint8_t{0});
        u0 = u1;
        continue;
      }
      const PreparedPrimitive& p = ws.prepared[pi];
      sample_run(p, z_row + u0, u0, n, fv, k,
                 RunSamples{ws.row_x.data(), ws.row_y.data(), ws.row_light.data(), measurable_row + u0});
      detail::texture_run(*p.material, ws.row_x.data(), ws.row_y.data(), ws.row_light.data(), n, noise_table,
                          ws.row_colour.data());
      const float* colour = ws.row_colour.data();
      std::uint8_t* out = bgr + 3 * u0;
      for (int j = 0; j < 3 * n; ++j) out[j] = to_byte(colour[j]);  // vectorises
      std::fill(label_row + u0, label_row + u1, p.instance_id);
      u0 = u1;
    }
  }
}

void SequenceRenderer::measure_depth(int index, RenderWorkspace& ws, RenderedFrame& frame) const {
  // The depth sensor, branch-free (it vectorises): every rule is evaluated per pixel, the valid
  // depths kept. Noise and dropout come from two hashes of (frame key, pixel index).
  const int width = spec_.camera.width_px;
  const int height = spec_.camera.height_px;
  const DepthSensorSettings& ds = spec_.render.depth;
  const float min_range = static_cast<float>(ds.min_range_m);
  const float max_range = static_cast<float>(ds.max_range_m);
  const float jump = static_cast<float>(ds.discontinuity_jump_m);
  // A pixel is dropped when its second hash is below p 2^32 (resolution 2^-32).
  const auto dropout_threshold =
      static_cast<std::uint32_t>(std::min(std::ldexp(ds.dropout_probability, 32), std::ldexp(1.0, 32) - 1));
  const float noise_scale = ds.noise_enabled ? 1.0f : 0.0f;
  const float noise_base = static_cast<float>(ds.noise_base_m);
  const float noise_quadratic = static_cast<float>(ds.noise_quadratic_per_m);
  const float noise_reference = static_cast<float>(ds.noise_reference_m);
  const float units = static_cast<float>(spec_.camera.depth_units_per_metre);
  const std::uint64_t frame_seed = splitmix64(spec_.seed ^ splitmix64(static_cast<std::uint64_t>(index)));
  const auto noise_key = static_cast<std::uint32_t>(frame_seed);
  const auto dropout_key = static_cast<std::uint32_t>(frame_seed >> 32);

  ws.largest_jump.resize(static_cast<std::size_t>(width));
  for (int v = 0; v < height; ++v) {
    const float* z_row = ws.depth_exact_m.ptr<float>(v);
    const float* z_up = ws.depth_exact_m.ptr<float>(v > 0 ? v - 1 : v);
    const float* z_down = ws.depth_exact_m.ptr<float>(v + 1 < height ? v + 1 : v);
    const std::uint8_t* measurable_row = ws.measurable.ptr<std::uint8_t>(v);
    std::uint16_t* depth_row = frame.depth.ptr<std::uint16_t>(v);
    float* jump_row = ws.largest_jump.data();
    // The largest depth difference to the 4 neighbours (the image border counts as no jump).
    auto vertical = [&](int u) { return std::max(std::abs(z_up[u] - z_row[u]), std::abs(z_down[u] - z_row[u])); };
    for (int u = 1; u + 1 < width; ++u) {
      const float horizontal = std::max(std::abs(z_row[u - 1] - z_row[u]), std::abs(z_row[u + 1] - z_row[u]));
      jump_row[u] = std::max(vertical(u), horizontal);
    }
    jump_row[0] = vertical(0);
    if (width > 1) {
      jump_row[0] = std::max(jump_row[0], std::abs(z_row[1] - z_row[0]));
      jump_row[width - 1] = std::max(vertical(width - 1), std::abs(z_row[width - 2] - z_row[width - 1]));
    }
    const auto row_start = static_cast<std::uint32_t>(v * width);
    for (int u = 0; u < width; ++u) {
      const float z = z_row[u];
      const auto pixel = row_start + static_cast<std::uint32_t>(u);
      const float dz = z - noise_reference;
      const float sigma = noise_scale * (noise_base + noise_quadratic * dz * dz);
      const float scaled = (z + sigma * gaussian_from_bits(pixel_hash(pixel, noise_key))) * units + 0.5f;
      // No hit (z infinite) fails the range test; values a 16-bit image cannot hold give no depth.
      const bool valid = (measurable_row[u] != 0) & (z >= min_range) & (z <= max_range) & (jump_row[u] <= jump) &
                         (pixel_hash(pixel, dropout_key) >= dropout_threshold) & (scaled >= 1.0f) & (scaled < 65536.0f);
      const float positive = scaled > 0.0f ? scaled : 0.0f;  // also maps nan to 0: a defined conversion
      const float in_range = positive < 65535.0f ? positive : 65535.0f;
      depth_row[u] = valid ? static_cast<std::uint16_t>(static_cast<std::int32_t>(in_range)) : std::uint16_t{0};
    }
  }
}

}  // namespace sim
}  // namespace cge
