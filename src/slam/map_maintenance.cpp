#include "cge/slam/map_maintenance.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/SVD>

#include "cge/bow/binary_descriptor.hpp"
#include "cge/slam/geometry/nearest_two.hpp"
#include "cge/slam/octave_scales.hpp"

namespace cge {
namespace slam {

void MapMaintenanceSettings::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("MapMaintenanceSettings: " + what); };
  if (!(min_found_ratio >= 0 && min_found_ratio <= 1)) fail("min_found_ratio must be in [0, 1]");
  if (young_point_age_keyframes < 0) fail("young_point_age_keyframes must not be negative");
  if (young_point_max_weighted_observations < 0) fail("young_point_max_weighted_observations must not be negative");
  if (mature_point_age_keyframes < 0) fail("mature_point_age_keyframes must not be negative");
  if (fuse_covisible_keyframes < 0 || fuse_second_neighbours < 0) fail("fuse neighbour counts must not be negative");
  if (!(fuse_radius_px > 0)) fail("fuse_radius_px must be > 0");
  if (!(fuse_chi2 > 0)) fail("fuse_chi2 must be > 0");
  if (fuse_max_hamming < 0 || fuse_max_hamming > 256) fail("fuse_max_hamming must be in 0 .. 256");
  if (!(close_depth_m > 0)) fail("close_depth_m must be > 0");
  if (redundant_min_observers < 1) fail("redundant_min_observers must be at least 1");
  if (redundant_octave_tolerance < 0) fail("redundant_octave_tolerance must not be negative");
  if (!(redundant_fraction >= 0 && redundant_fraction <= 1)) fail("redundant_fraction must be in [0, 1]");
  if (triangulation_neighbours < 0) fail("triangulation_neighbours must not be negative");
  if (triangulation_max_hamming < 0 || triangulation_max_hamming > 256)
    fail("triangulation_max_hamming must be in 0 .. 256");
  if (!(triangulation_ratio > 0 && triangulation_ratio <= 1)) fail("triangulation_ratio must be in (0, 1]");
  if (!(triangulation_epipolar_chi2 > 0)) fail("triangulation_epipolar_chi2 must be > 0");
  if (!(triangulation_epipole_px >= 0)) fail("triangulation_epipole_px must not be negative");
  if (!(triangulation_chi2 > 0)) fail("triangulation_chi2 must be > 0");
  if (!(triangulation_max_parallax_cos > 0 && triangulation_max_parallax_cos <= 1))
    fail("triangulation_max_parallax_cos must be in (0, 1]");
  if (!(triangulation_scale_tolerance >= 1)) fail("triangulation_scale_tolerance must be >= 1");
  if (!(triangulation_min_baseline_ratio >= 0)) fail("triangulation_min_baseline_ratio must not be negative");
}

namespace {

bool has_depth(const Keyframe& kf, int i) {
  const double z = kf.points_camera_m[static_cast<std::size_t>(i)].z();
  return std::isfinite(z) && z > 0;
}

bool is_static(const Keyframe& kf, int i) {
  return kf.labels[static_cast<std::size_t>(i)] == FeatureLabel::static_feature;
}

void check_live(const Map& map, int keyframe_id, const char* where) {
  if (keyframe_id < 0 || keyframe_id >= map.keyframe_count()) {
    throw std::invalid_argument(std::string(where) + ": keyframe " + std::to_string(keyframe_id) + " is not in 0 .. " +
                                std::to_string(map.keyframe_count() - 1));
  }
  if (map.keyframe(keyframe_id).culled) {
    throw std::invalid_argument(std::string(where) + ": keyframe " + std::to_string(keyframe_id) + " is culled");
  }
}

void check_scale_factor(double orb_scale_factor, const char* where) {
  if (!(orb_scale_factor >= 1) || !std::isfinite(orb_scale_factor)) {
    throw std::invalid_argument(std::string(where) + ": orb_scale_factor must be finite and >= 1");
  }
}

constexpr double kGridCellPx = 16;  // bucket size of the keypoint grid, pixels

/// The static keypoints of a keyframe bucketed by undistorted pixel, for window queries.
class StaticKeypointGrid {
 public:
  StaticKeypointGrid(const Keyframe& kf, const cv::Size& image_size)
      : cols_(std::max(1, static_cast<int>(std::ceil(image_size.width / kGridCellPx)))),
        rows_(std::max(1, static_cast<int>(std::ceil(image_size.height / kGridCellPx)))),
        cells_(static_cast<std::size_t>(cols_ * rows_)) {
    for (int i = 0; i < static_cast<int>(kf.keypoints.size()); ++i) {
      if (!is_static(kf, i)) continue;
      const cv::Point2f& p = kf.undistorted_px[static_cast<std::size_t>(i)];
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      cells_[static_cast<std::size_t>(row(p.y) * cols_ + col(p.x))].push_back(i);
      max_octave_ = std::max(max_octave_, kf.keypoints[static_cast<std::size_t>(i)].octave);
    }
  }
  int max_octave() const { return max_octave_; }
  /// Calls f(i) for the keypoints in the cells overlapping the square window.
  template <typename F>
  void for_each_near(double u, double v, double radius, F&& f) const {
    for (int r = row(v - radius); r <= row(v + radius); ++r) {
      for (int c = col(u - radius); c <= col(u + radius); ++c) {
        for (const int i : cells_[static_cast<std::size_t>(r * cols_ + c)]) f(i);
      }
    }
  }

 private:
  int col(double x) const { return std::clamp(static_cast<int>(std::floor(x / kGridCellPx)), 0, cols_ - 1); }
  int row(double y) const { return std::clamp(static_cast<int>(std::floor(y / kGridCellPx)), 0, rows_ - 1); }
  int cols_, rows_;
  int max_octave_ = 0;
  std::vector<std::vector<int>> cells_;
};

bool observes(const MapPoint& p, int keyframe_id) {
  return std::any_of(p.observations.begin(), p.observations.end(),
                     [&](const Observation& o) { return o.keyframe_id == keyframe_id; });
}

/// ORBmatcher::Fuse for one point into one keyframe (see fuse_map_points).
void fuse_point(Map& map, std::int64_t point_id, int target, const Eigen::Isometry3d& T_camera_world,
                const StaticKeypointGrid& grid, const PinholeIntrinsics<double>& intrinsics,
                const cv::Size& image_size, const OctaveScales& scales, const MapMaintenanceSettings& s,
                FusionReport& report) {
  const MapPoint& p = map.map_point(point_id);
  if (p.bad || observes(p, target)) return;
  const Keyframe& kf = map.keyframe(target);
  const Eigen::Vector3d p_camera = T_camera_world * p.position_world;
  if (!(p_camera.z() > 0)) return;
  const Eigen::Vector2d uv = intrinsics.project(p_camera);
  if (!(uv.x() >= 0 && uv.x() < image_size.width && uv.y() >= 0 && uv.y() < image_size.height)) return;
  ++report.projections;
  const std::uint8_t* descriptor = p.descriptor.ptr<std::uint8_t>(0);
  int best_distance = INT_MAX, best = -1;
  grid.for_each_near(uv.x(), uv.y(), s.fuse_radius_px * scales(grid.max_octave()), [&](int i) {
    const double sigma = scales(kf.keypoints[static_cast<std::size_t>(i)].octave);
    const cv::Point2f& kp = kf.undistorted_px[static_cast<std::size_t>(i)];
    const double d2 = (kp.x - uv.x()) * (kp.x - uv.x()) + (kp.y - uv.y()) * (kp.y - uv.y());
    const double radius = s.fuse_radius_px * sigma;
    if (d2 > radius * radius || !(d2 / (sigma * sigma) < s.fuse_chi2)) return;
    const int d = bow::hamming_distance_32_bytes(descriptor, kf.descriptors.ptr<std::uint8_t>(i));
    if (d < best_distance || (d == best_distance && i < best)) {
      best_distance = d;
      best = i;
    }
  });
  if (best < 0 || best_distance > s.fuse_max_hamming) return;
  const std::int64_t in_keyframe = kf.map_point_ids[static_cast<std::size_t>(best)];
  if (in_keyframe >= 0) {
    if (weighted_observations(map, map.map_point(in_keyframe)) > weighted_observations(map, p)) {
      map.replace_map_point(point_id, in_keyframe);
    } else {
      map.replace_map_point(in_keyframe, point_id);
    }
    ++report.points_replaced;
  } else {
    map.add_observation(point_id, target, best);
    ++report.observations_added;
  }
}

}  // namespace

int weighted_observations(const Map& map, const MapPoint& point) {
  int n = 0;
  for (const Observation& o : point.observations) n += has_depth(map.keyframe(o.keyframe_id), o.keypoint_index) ? 2 : 1;
  return n;
}

MapPointCullingReport cull_recent_map_points(Map& map, std::vector<std::int64_t>& recent, int current_keyframe,
                                             const MapMaintenanceSettings& s) {
  check_live(map, current_keyframe, "cull_recent_map_points");
  for (const std::int64_t id : recent) {
    const MapPoint& p = map.map_point(id);  // throws for an unknown id
    if (p.created_by_keyframe < 0) {
      throw std::invalid_argument("cull_recent_map_points: map point " + std::to_string(id) +
                                  " has no created_by_keyframe");
    }
  }
  MapPointCullingReport report;
  std::vector<std::int64_t> still_recent;
  for (const std::int64_t id : recent) {
    ++report.checked;
    const MapPoint& p = map.map_point(id);
    const int age = current_keyframe - p.created_by_keyframe;
    if (p.bad) {
      ++report.dropped_bad;
    } else if (static_cast<double>(p.found) / static_cast<double>(p.visible) < s.min_found_ratio) {
      map.erase_map_point(id);
      ++report.erased_low_found_ratio;
      report.erased.push_back(id);
    } else if (age >= s.young_point_age_keyframes &&
               weighted_observations(map, p) <= s.young_point_max_weighted_observations) {
      map.erase_map_point(id);
      ++report.erased_few_observations;
      report.erased.push_back(id);
    } else if (age >= s.mature_point_age_keyframes) {
      ++report.matured;
    } else {
      still_recent.push_back(id);
    }
  }
  recent = std::move(still_recent);
  return report;
}

FusionReport fuse_map_points(Map& map, int keyframe_id, const PinholeIntrinsics<double>& intrinsics,
                             const cv::Size& image_size, double orb_scale_factor, const MapMaintenanceSettings& s) {
  check_live(map, keyframe_id, "fuse_map_points");
  check_scale_factor(orb_scale_factor, "fuse_map_points");
  if (image_size.width <= 0 || image_size.height <= 0) {
    throw std::invalid_argument("fuse_map_points: the image size " + std::to_string(image_size.width) + " x " +
                                std::to_string(image_size.height) + " is empty");
  }
  FusionReport report;
  for (const int first : map.covisible_keyframes(keyframe_id, s.fuse_covisible_keyframes)) {
    report.targets.push_back(first);
    for (const int second : map.covisible_keyframes(first, s.fuse_second_neighbours)) {
      if (second != keyframe_id) report.targets.push_back(second);
    }
  }
  std::sort(report.targets.begin(), report.targets.end());
  report.targets.erase(std::unique(report.targets.begin(), report.targets.end()), report.targets.end());

  // The keyframe's points into each target.
  std::vector<std::int64_t> own;
  for (const std::int64_t p : map.keyframe(keyframe_id).map_point_ids) {
    if (p >= 0) own.push_back(p);
  }
  const OctaveScales scales(orb_scale_factor);
  for (const int target : report.targets) {
    const StaticKeypointGrid grid(map.keyframe(target), image_size);
    const Eigen::Isometry3d T_camera_world = map.keyframe(target).T_world_camera.inverse();
    for (const std::int64_t p : own) {
      fuse_point(map, p, target, T_camera_world, grid, intrinsics, image_size, scales, s, report);
    }
  }
  // The targets' points into the keyframe.
  std::vector<std::int64_t> theirs;
  for (const int target : report.targets) {
    for (const std::int64_t p : map.keyframe(target).map_point_ids) {
      if (p >= 0) theirs.push_back(p);
    }
  }
  std::sort(theirs.begin(), theirs.end());
  theirs.erase(std::unique(theirs.begin(), theirs.end()), theirs.end());
  const StaticKeypointGrid grid(map.keyframe(keyframe_id), image_size);
  const Eigen::Isometry3d T_camera_world = map.keyframe(keyframe_id).T_world_camera.inverse();
  for (const std::int64_t p : theirs) {
    fuse_point(map, p, keyframe_id, T_camera_world, grid, intrinsics, image_size, scales, s, report);
  }
  return report;
}

KeyframeCullingReport cull_redundant_keyframes(Map& map, int keyframe_id, const MapMaintenanceSettings& s) {
  check_live(map, keyframe_id, "cull_redundant_keyframes");
  KeyframeCullingReport report;
  std::vector<int> candidates = map.covisible_keyframes(keyframe_id, -1);
  std::sort(candidates.begin(), candidates.end());
  for (const int k : candidates) {
    if (k == 0 || k == keyframe_id || map.keyframe(k).culled) continue;
    report.examined.push_back(k);
    const Keyframe& kf = map.keyframe(k);
    int counted = 0, redundant = 0;
    for (std::size_t i = 0; i < kf.map_point_ids.size(); ++i) {
      const std::int64_t id = kf.map_point_ids[i];
      if (id < 0) continue;
      const double z = kf.points_camera_m[i].z();
      if (!(std::isfinite(z) && z > 0 && z <= s.close_depth_m)) continue;
      ++counted;
      const int octave = kf.keypoints[i].octave;
      int observers = 0;
      for (const Observation& o : map.map_point(id).observations) {
        if (o.keyframe_id == k) continue;
        const int other_octave =
            map.keyframe(o.keyframe_id).keypoints[static_cast<std::size_t>(o.keypoint_index)].octave;
        if (other_octave <= octave + s.redundant_octave_tolerance) ++observers;
        if (observers >= s.redundant_min_observers) break;
      }
      if (observers >= s.redundant_min_observers) ++redundant;
    }
    if (!(redundant > s.redundant_fraction * counted)) continue;
    const std::vector<int> parent = map.covisible_keyframes(k, 1);
    if (parent.empty()) continue;  // shares nothing with a live keyframe: no pose to hang from
    map.cull_keyframe(k, parent.front());
    report.culled.push_back(k);
  }
  return report;
}

namespace {

/// Camera-from-world rotation and translation of a pose.
struct CameraFromWorld {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  Eigen::Vector3d centre;  ///< camera centre in the world
  explicit CameraFromWorld(const Eigen::Isometry3d& T_world_camera)
      : R(T_world_camera.linear().transpose()),
        t(-(T_world_camera.linear().transpose() * T_world_camera.translation())),
        centre(T_world_camera.translation()) {}
};

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

double median_point_depth(const Map& map, const Keyframe& kf, const CameraFromWorld& c) {
  std::vector<double> z;
  for (const std::int64_t p : kf.map_point_ids) {
    if (p >= 0) z.push_back((c.R * map.map_point(p).position_world + c.t).z());
  }
  if (z.empty()) return std::nan("");
  const auto mid = z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2);
  std::nth_element(z.begin(), mid, z.end());
  return *mid;
}

/// Linear (DLT) triangulation from normalised image coordinates of two cameras; NaN when degenerate.
Eigen::Vector3d triangulate_dlt(const Eigen::Vector2d& x1, const CameraFromWorld& c1, const Eigen::Vector2d& x2,
                                const CameraFromWorld& c2) {
  Eigen::Matrix<double, 3, 4> P1, P2;
  P1 << c1.R, c1.t;
  P2 << c2.R, c2.t;
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (X(3) == 0) return Eigen::Vector3d::Constant(std::nan(""));
  return X.head<3>() / X(3);
}

bool usable_for_triangulation(const Keyframe& kf, int i) {
  return is_static(kf, i) && kf.map_point_ids[static_cast<std::size_t>(i)] < 0 && !has_depth(kf, i);
}

}  // namespace

TriangulationReport triangulate_new_points(Map& map, int keyframe_id, const PinholeIntrinsics<double>& K,
                                           double scale_factor, const MapMaintenanceSettings& s) {
  check_live(map, keyframe_id, "triangulate_new_points");
  check_scale_factor(scale_factor, "triangulate_new_points");
  const OctaveScales level_scale(scale_factor);
  TriangulationReport report;
  report.neighbours = map.covisible_keyframes(keyframe_id, s.triangulation_neighbours);
  std::sort(report.neighbours.begin(), report.neighbours.end());
  const CameraFromWorld c1(map.keyframe(keyframe_id).T_world_camera);
  const auto normalised = [&](const cv::Point2f& px) {
    return Eigen::Vector2d((px.x - K.cx_px) / K.fx_px, (px.y - K.cy_px) / K.fy_px);
  };
  Eigen::Matrix3d K_inv = Eigen::Matrix3d::Identity();
  K_inv(0, 0) = 1 / K.fx_px;
  K_inv(1, 1) = 1 / K.fy_px;
  K_inv(0, 2) = -K.cx_px / K.fx_px;
  K_inv(1, 2) = -K.cy_px / K.fy_px;
  for (const int n : report.neighbours) {
    const Keyframe& kf1 = map.keyframe(keyframe_id);
    const Keyframe& kf2 = map.keyframe(n);
    const CameraFromWorld c2(kf2.T_world_camera);
    const double median_depth = median_point_depth(map, kf2, c2);
    if (!(median_depth > 0) || (c2.centre - c1.centre).norm() / median_depth < s.triangulation_min_baseline_ratio) {
      continue;
    }
    // Epipolar geometry: x2^T F21 x1 = 0 with x2 = R21 x1 + t21 in camera coordinates.
    const Eigen::Matrix3d R21 = c2.R * c1.R.transpose();
    const Eigen::Vector3d t21 = c2.t - R21 * c1.t;
    const Eigen::Matrix3d F21 = K_inv.transpose() * skew(t21) * R21 * K_inv;
    const Eigen::Vector3d centre1_in_2 = c2.R * c1.centre + c2.t;
    const bool has_epipole = centre1_in_2.z() > 0;
    const Eigen::Vector2d epipole = has_epipole ? K.project(centre1_in_2) : Eigen::Vector2d::Zero();
    std::vector<char> used(kf2.keypoints.size(), 0);
    std::vector<std::pair<int, int>> matches;  // (keypoint in kf1, keypoint in kf2)
    for (int i = 0; i < static_cast<int>(kf1.keypoints.size()); ++i) {
      if (!usable_for_triangulation(kf1, i)) continue;
      const cv::Point2f& p1 = kf1.undistorted_px[static_cast<std::size_t>(i)];
      const Eigen::Vector3d line = F21 * Eigen::Vector3d(p1.x, p1.y, 1);
      const double line_norm2 = line.x() * line.x() + line.y() * line.y();
      if (!(line_norm2 > 0)) continue;
      const std::uint8_t* d1 = kf1.descriptors.ptr<std::uint8_t>(i);
      NearestTwo nearest;
      for (int j = 0; j < static_cast<int>(kf2.keypoints.size()); ++j) {
        if (used[static_cast<std::size_t>(j)] || !usable_for_triangulation(kf2, j)) continue;
        const cv::Point2f& p2 = kf2.undistorted_px[static_cast<std::size_t>(j)];
        const double sigma2 = std::pow(level_scale(kf2.keypoints[static_cast<std::size_t>(j)].octave), 2);
        if (has_epipole) {
          const double ex = p2.x - epipole.x(), ey = p2.y - epipole.y();
          const double limit = s.triangulation_epipole_px * s.triangulation_epipole_px *
                               level_scale(kf2.keypoints[static_cast<std::size_t>(j)].octave);
          if (ex * ex + ey * ey < limit) continue;
        }
        const double num = line.x() * p2.x + line.y() * p2.y + line.z();
        if (!(num * num / line_norm2 < s.triangulation_epipolar_chi2 * sigma2)) continue;
        nearest.add(j, bow::hamming_distance_32_bytes(d1, kf2.descriptors.ptr<std::uint8_t>(j)));
      }
      if (!nearest.passes(s.triangulation_max_hamming, s.triangulation_ratio)) continue;
      used[static_cast<std::size_t>(nearest.best_index)] = 1;
      matches.emplace_back(i, nearest.best_index);
    }
    report.matches += static_cast<int>(matches.size());

    for (const auto& [i, j] : matches) {
      const cv::KeyPoint& kp1 = kf1.keypoints[static_cast<std::size_t>(i)];
      const cv::KeyPoint& kp2 = kf2.keypoints[static_cast<std::size_t>(j)];
      const Eigen::Vector2d x1 = normalised(kf1.undistorted_px[static_cast<std::size_t>(i)]);
      const Eigen::Vector2d x2 = normalised(kf2.undistorted_px[static_cast<std::size_t>(j)]);
      const Eigen::Vector3d ray1 = c1.R.transpose() * Eigen::Vector3d(x1.x(), x1.y(), 1);
      const Eigen::Vector3d ray2 = c2.R.transpose() * Eigen::Vector3d(x2.x(), x2.y(), 1);
      const double cos_parallax = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
      if (!(cos_parallax > 0 && cos_parallax < s.triangulation_max_parallax_cos)) continue;
      const Eigen::Vector3d X = triangulate_dlt(x1, c1, x2, c2);
      if (!X.allFinite()) continue;
      const auto reprojects = [&](const CameraFromWorld& c, const cv::Point2f& px, const cv::KeyPoint& kp) {
        const Eigen::Vector3d p = c.R * X + c.t;
        if (!(p.z() > 0)) return false;
        const Eigen::Vector2d uv = K.project(p);
        const double sigma = level_scale(kp.octave);
        const double e2 = (uv.x() - px.x) * (uv.x() - px.x) + (uv.y() - px.y) * (uv.y() - px.y);
        return e2 / (sigma * sigma) < s.triangulation_chi2;
      };
      if (!reprojects(c1, kf1.undistorted_px[static_cast<std::size_t>(i)], kp1) ||
          !reprojects(c2, kf2.undistorted_px[static_cast<std::size_t>(j)], kp2)) {
        continue;
      }
      const double dist1 = (X - c1.centre).norm(), dist2 = (X - c2.centre).norm();
      if (!(dist1 > 0 && dist2 > 0)) continue;
      const double ratio_distance = dist2 / dist1;
      const double ratio_octave = level_scale(kp1.octave) / level_scale(kp2.octave);
      const double tolerance = s.triangulation_scale_tolerance * scale_factor;
      if (ratio_distance * tolerance < ratio_octave || ratio_distance > ratio_octave * tolerance) continue;
      const std::int64_t id = map.add_map_point(X, kf1.descriptors.row(i), keyframe_id);
      map.add_observation(id, keyframe_id, i);
      map.add_observation(id, n, j);
      report.created.push_back(id);
    }
  }
  return report;
}

}  // namespace slam
}  // namespace cge
