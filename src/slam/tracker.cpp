#include "cge/slam/tracker.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "cge/slam/geometry/descriptor_matching.hpp"
#include "cge/slam/geometry/pnp_ransac.hpp"
#include "cge/slam/geometry/rigid_pose_ransac.hpp"

namespace cge {
namespace slam {

const char* to_string(TrackingState state) {
  switch (state) {
    case TrackingState::initialised:
      return "initialised";
    case TrackingState::tracked:
      return "tracked";
    case TrackingState::odometry:
      return "odometry";
    case TrackingState::relocalised:
      return "relocalised";
    case TrackingState::lost:
      return "lost";
  }
  return "invalid";
}

namespace {

constexpr int kMinPnpPoints = 6;          // fewer correspondences cannot give a RANSAC pose
constexpr double kMinPointDepthM = 0.05;  // map points closer to the camera are not projected

}  // namespace

struct Tracker::Attempt {
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  int matches = 0;
  int inliers = 0;
  std::vector<std::int64_t> map_point_ids;
  std::vector<std::int64_t> visible;  ///< points the last projection search put inside the image
};

Tracker::Tracker(const TrackerSettings& settings, const PinholeIntrinsics<double>& intrinsics, double orb_scale_factor)
    : settings_(settings),
      intrinsics_(intrinsics),
      orb_scale_factor_(orb_scale_factor),
      refiner_(settings.refinement) {}

std::vector<std::int64_t> Tracker::local_map_points(const Map& map, int centre) const {
  std::set<int> keyframes;
  const int n = map.keyframe_count();
  for (int id = std::max(0, n - settings_.local_recent_keyframes); id < n; ++id) keyframes.insert(id);
  if (centre >= 0 && centre < n) {
    keyframes.insert(centre);
    for (const int id : map.covisible_keyframes(centre, settings_.local_covisible_keyframes)) {
      keyframes.insert(id);
    }
  }
  std::vector<std::int64_t> points;
  for (const int id : keyframes) {
    for (const std::int64_t p : map.keyframe(id).map_point_ids) {
      if (p >= 0) points.push_back(p);
    }
  }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  return points;
}

ProjectionSearch Tracker::projection_search(double radius_px, bool require_in_image) const {
  ProjectionSearch search;
  search.radius_px = radius_px;
  search.max_hamming = settings_.max_hamming;
  search.ratio = settings_.ratio;
  search.min_depth_m = kMinPointDepthM;
  search.require_in_image = require_in_image;
  return search;
}

int Tracker::match_by_projection(const Frame& frame, const Map& map, const std::vector<std::int64_t>& points,
                                 const Eigen::Isometry3d& T_world_camera, double radius_px,
                                 std::vector<std::int64_t>& matches, std::vector<std::int64_t>* visible) const {
  std::vector<PointToProject> projected;
  projected.reserve(points.size());
  for (const std::int64_t id : points) {
    const MapPoint& mp = map.map_point(id);
    projected.push_back(PointToProject{mp.position_world, mp.descriptor.ptr<std::uint8_t>(0)});
  }
  std::vector<int> in_image;
  const std::vector<int> source = cge::slam::match_by_projection(frame, KeypointGrid(frame), intrinsics_, projected,
                                                                 T_world_camera, projection_search(radius_px, true),
                                                                 visible != nullptr ? &in_image : nullptr);
  if (visible != nullptr) {
    for (const int k : in_image) visible->push_back(points[static_cast<std::size_t>(k)]);
  }
  matches.assign(static_cast<std::size_t>(frame.size()), -1);
  int count = 0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (source[i] < 0) continue;
    matches[i] = points[static_cast<std::size_t>(source[i])];
    ++count;
  }
  return count;
}

bool Tracker::ransac_pose(const Frame& frame, const Map& map, const std::vector<std::int64_t>& matches, int min_inliers,
                          Eigen::Isometry3d& T_world_camera) const {
  std::vector<int> keypoints;
  std::vector<Eigen::Vector3d> points_world;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (matches[i] < 0) continue;
    keypoints.push_back(static_cast<int>(i));
    points_world.push_back(map.map_point(matches[i]).position_world);
  }
  return ransac_pose(frame, keypoints, points_world, min_inliers, T_world_camera);
}

bool Tracker::ransac_pose(const Frame& frame, const std::vector<int>& keypoints,
                          const std::vector<Eigen::Vector3d>& points_world, int min_inliers,
                          Eigen::Isometry3d& T_world_camera) const {
  if (settings_.ransac_solver == TrackingRansacSolver::rigid) {
    return rigid_ransac_pose(frame, keypoints, points_world, min_inliers, T_world_camera);
  }
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (std::size_t k = 0; k < keypoints.size(); ++k) {
    const Eigen::Vector3d& X = points_world[k];
    const cv::Point2f& uv = frame.undistorted_px[static_cast<std::size_t>(keypoints[k])];
    object.emplace_back(X.x(), X.y(), X.z());
    image.emplace_back(uv.x, uv.y);
  }
  if (static_cast<int>(object.size()) < std::max(kMinPnpPoints, min_inliers)) return false;
  PnpRansacSettings pnp;
  pnp.iterations = settings_.pnp_iterations;
  pnp.reprojection_px = settings_.pnp_reprojection_px;
  pnp.confidence = settings_.pnp_confidence;
  const PnpRansacResult solved = solve_pnp_ransac(object, image, intrinsics_, pnp);
  if (!solved.ok || static_cast<int>(solved.inliers.size()) < std::max(kMinPnpPoints, min_inliers)) return false;
  T_world_camera = solved.T_camera_object.inverse();
  return T_world_camera.matrix().allFinite();
}

bool Tracker::rigid_ransac_pose(const Frame& frame, const std::vector<int>& keypoints,
                                const std::vector<Eigen::Vector3d>& points_world, int min_inliers,
                                Eigen::Isometry3d& T_world_camera) const {
  if (static_cast<int>(keypoints.size()) < std::max(kMinPnpPoints, min_inliers)) return false;
  std::vector<Eigen::Vector2d> pixels(keypoints.size());
  std::vector<Eigen::Vector3d> points_camera(keypoints.size());
  for (std::size_t k = 0; k < keypoints.size(); ++k) {
    const auto i = static_cast<std::size_t>(keypoints[k]);
    pixels[k] = Eigen::Vector2d(frame.undistorted_px[i].x, frame.undistorted_px[i].y);
    points_camera[k] = frame.points_camera_m[i];  // NaN without depth: scored, never sampled
  }
  RigidPoseRansacSettings ransac;
  ransac.max_iterations = settings_.pnp_iterations;
  ransac.reprojection_px = settings_.pnp_reprojection_px;
  ransac.confidence = settings_.pnp_confidence;
  const RigidPoseRansacResult solved = solve_rigid_pose_ransac(points_world, pixels, points_camera, intrinsics_, ransac);
  if (!solved.ok || static_cast<int>(solved.inliers.size()) < std::max(kMinPnpPoints, min_inliers)) return false;
  T_world_camera = solved.T_camera_world.inverse();
  return T_world_camera.matrix().allFinite();
}

void Tracker::add_depth(const Frame& frame, int keypoint, PoseObservation& o) const {
  if (!(settings_.refinement_depth_sigma_per_m > 0) || !frame.has_depth(keypoint)) return;
  o.depth_m = frame.points_camera_m[static_cast<std::size_t>(keypoint)].z();
  o.sigma_depth_m = settings_.refinement_depth_sigma_per_m * o.depth_m * o.depth_m;
}

bool Tracker::refine_pose(const Frame& frame, const Map& map, const std::vector<std::int64_t>& matches,
                          const Eigen::Isometry3d& T_initial, int min_inliers, Attempt& out) const {
  std::vector<PoseObservation> observations;
  std::vector<int> keypoint_of;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (matches[i] < 0) continue;
    PoseObservation o;
    o.point_world_m = map.map_point(matches[i]).position_world;
    o.pixel_px = Eigen::Vector2d(frame.undistorted_px[i].x, frame.undistorted_px[i].y);
    o.sigma_px = keypoint_sigma_px(frame.keypoints[i], orb_scale_factor_);
    add_depth(frame, static_cast<int>(i), o);
    observations.push_back(o);
    keypoint_of.push_back(static_cast<int>(i));
  }
  out.matches = static_cast<int>(observations.size());
  if (out.matches < std::max(kMinPnpPoints, min_inliers)) return false;
  PoseRefinementResult refined;
  try {
    refined = refiner_.refine(intrinsics_, observations, T_initial);
  } catch (const std::invalid_argument&) {
    return false;  // too few points in front of the initial pose: a degenerate solution
  }
  out.T_world_camera = refined.T_world_camera;
  out.inliers = refined.inlier_count;
  out.map_point_ids.assign(matches.size(), -1);
  for (std::size_t k = 0; k < observations.size(); ++k) {
    if (!refined.inliers[k]) continue;
    const auto i = static_cast<std::size_t>(keypoint_of[k]);
    out.map_point_ids[i] = matches[i];
  }
  return out.inliers >= min_inliers;
}

bool Tracker::refine_with_local_map(const Frame& frame, const Map& map, const std::vector<std::int64_t>& points,
                                    const Eigen::Isometry3d& T_initial, Attempt& out) const {
  std::vector<std::int64_t> matches;
  out.visible.clear();
  match_by_projection(frame, map, points, T_initial, settings_.search_radius_px, matches, &out.visible);
  return refine_pose(frame, map, matches, T_initial, settings_.min_inliers, out);
}

bool Tracker::track_with_radius(const Frame& frame, const Map& map, const std::vector<std::int64_t>& points,
                                const Eigen::Isometry3d& prediction, double radius_px, Attempt& out) const {
  std::vector<std::int64_t> matches;
  if (match_by_projection(frame, map, points, prediction, radius_px, matches) < settings_.min_matches) return false;
  // A first pose from the matches of the prediction (refined from the prediction, or RANSAC), then
  // the matches of that pose refined (the second search finds the points the prediction missed).
  const auto within_jump = [&](const Eigen::Isometry3d& T) {
    return (T.translation() - prediction.translation()).norm() <= settings_.max_jump_m;
  };
  Eigen::Isometry3d T_first;
  Attempt direct;
  const bool refined_from_prediction = settings_.ransac_only_on_failure &&
                                       refine_pose(frame, map, matches, prediction, settings_.min_inliers, direct) &&
                                       within_jump(direct.T_world_camera);
  if (refined_from_prediction) {
    T_first = direct.T_world_camera;
  } else if (!ransac_pose(frame, map, matches, settings_.min_inliers, T_first) || !within_jump(T_first)) {
    return false;
  }
  if (!refine_with_local_map(frame, map, points, T_first, out)) return false;
  return within_jump(out.T_world_camera);
}

bool Tracker::track_local_map(const Frame& frame, const Map& map, const Eigen::Isometry3d& prediction,
                              Attempt& out) const {
  const std::vector<std::int64_t> points = local_map_points(map, reference_keyframe_);
  if (track_with_radius(frame, map, points, prediction, settings_.search_radius_px, out)) return true;
  // A prediction off by more than the window still finds enough matches on repeated texture, most
  // of them wrong: retry on the failure itself, not only on a low match count.
  out = Attempt{};
  return track_with_radius(frame, map, points, prediction, settings_.search_radius_px * settings_.wide_search_factor,
                           out);
}

bool Tracker::track_last_frame(const Frame& frame, const Map& map, const Eigen::Isometry3d& prediction,
                               Attempt& out) const {
  if (last_points_camera_m_.empty()) return false;
  // Projection matching of the previous frame's static keypoints with depth (temporary points, as
  // ORB-SLAM2's RGB-D motion model does) within the wide window: one frame of motion at most.
  std::vector<PointToProject> projected;
  projected.reserve(last_points_camera_m_.size());
  for (std::size_t k = 0; k < last_points_camera_m_.size(); ++k) {
    projected.push_back(PointToProject{T_world_last_ * last_points_camera_m_[k],
                                       last_descriptors_.ptr<std::uint8_t>(static_cast<int>(k))});
  }
  // No in-image test: a point projecting just outside the image still finds keypoints at its edge.
  const std::vector<int> source = cge::slam::match_by_projection(
      frame, KeypointGrid(frame), intrinsics_, projected, prediction,
      projection_search(settings_.search_radius_px * settings_.wide_search_factor, false));
  std::vector<int> keypoints;
  std::vector<Eigen::Vector3d> points_world;
  for (int i = 0; i < frame.size(); ++i) {
    const int k = source[static_cast<std::size_t>(i)];
    if (k < 0) continue;
    keypoints.push_back(i);
    points_world.push_back(projected[static_cast<std::size_t>(k)].position_world);
  }
  if (static_cast<int>(keypoints.size()) < settings_.min_matches) return false;
  Eigen::Isometry3d T_ransac;
  if (!ransac_pose(frame, keypoints, points_world, settings_.min_inliers, T_ransac)) return false;
  std::vector<PoseObservation> observations;
  for (std::size_t k = 0; k < keypoints.size(); ++k) {
    const auto i = static_cast<std::size_t>(keypoints[k]);
    const cv::KeyPoint& kp = frame.keypoints[i];
    PoseObservation o;
    o.point_world_m = points_world[k];
    o.pixel_px = Eigen::Vector2d(frame.undistorted_px[i].x, frame.undistorted_px[i].y);
    o.sigma_px = keypoint_sigma_px(kp, orb_scale_factor_);
    add_depth(frame, keypoints[k], o);
    observations.push_back(o);
  }
  PoseRefinementResult refined;
  try {
    refined = refiner_.refine(intrinsics_, observations, T_ransac);
  } catch (const std::invalid_argument&) {
    return false;
  }
  if (refined.inlier_count < settings_.min_inliers) return false;
  if ((refined.T_world_camera.translation() - prediction.translation()).norm() > settings_.max_jump_m) return false;
  // The map points that agree with the odometry pose become the frame's tracked points (few: the
  // map lags behind the view, so the keyframe policy's tracking guard makes this frame a keyframe
  // and its depth fills the map where the view has gone).
  out = Attempt{};
  out.T_world_camera = refined.T_world_camera;
  std::vector<std::int64_t> matches;
  out.matches = match_by_projection(frame, map, local_map_points(map, reference_keyframe_), out.T_world_camera,
                                    settings_.search_radius_px, matches, &out.visible);
  out.map_point_ids.assign(matches.size(), -1);
  const Eigen::Isometry3d T_camera_world_refined = out.T_world_camera.inverse();
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (matches[i] < 0) continue;
    const Eigen::Vector3d p_camera = T_camera_world_refined * map.map_point(matches[i]).position_world;
    const Eigen::Vector2d r =
        intrinsics_.project(p_camera) - Eigen::Vector2d(frame.undistorted_px[i].x, frame.undistorted_px[i].y);
    const double sigma = keypoint_sigma_px(frame.keypoints[i], orb_scale_factor_);
    if (r.squaredNorm() / (sigma * sigma) > settings_.refinement.chi2_threshold_2dof) continue;
    out.map_point_ids[i] = matches[i];
    ++out.inliers;
  }
  return true;
}

void Tracker::remember_last_frame(const Frame& frame) {
  last_points_camera_m_.clear();
  last_descriptors_ = cv::Mat();
  for (int i = 0; i < frame.size(); ++i) {
    if (!frame.is_static(i) || !frame.has_depth(i)) continue;
    last_points_camera_m_.push_back(frame.points_camera_m[static_cast<std::size_t>(i)]);
    last_descriptors_.push_back(frame.descriptors.row(i));
  }
}

bool Tracker::relocalise(const Frame& frame, const Map& map, Attempt& out) const {
  std::vector<int> query_index;
  for (int i = 0; i < frame.size(); ++i) {
    if (frame.is_static(i)) query_index.push_back(i);
  }
  if (query_index.empty()) return false;
  cv::Mat query(static_cast<int>(query_index.size()), frame.descriptors.cols, frame.descriptors.type());
  for (std::size_t q = 0; q < query_index.size(); ++q)
    frame.descriptors.row(query_index[q]).copyTo(query.row(static_cast<int>(q)));
  // Candidates: the source's (anywhere in the map, best first), then the last keyframes, each once.
  const int n = map.keyframe_count();
  std::vector<int> candidates;
  if (candidate_source_) {
    for (const int id : candidate_source_(frame)) {
      if (id < 0 || id >= n) continue;
      if (static_cast<int>(candidates.size()) >= settings_.relocalisation_candidates) break;
      candidates.push_back(id);
    }
  }
  for (int id = n - 1; id >= std::max(0, n - settings_.relocalisation_keyframes); --id) {
    if (std::find(candidates.begin(), candidates.end(), id) == candidates.end()) candidates.push_back(id);
  }
  for (const int id : candidates) {
    const Keyframe& kf = map.keyframe(id);
    std::vector<std::int64_t> train_point;
    cv::Mat train;
    for (std::size_t k = 0; k < kf.map_point_ids.size(); ++k) {
      if (kf.map_point_ids[k] < 0) continue;
      train.push_back(kf.descriptors.row(static_cast<int>(k)));
      train_point.push_back(kf.map_point_ids[k]);
    }
    if (static_cast<int>(train_point.size()) < settings_.min_relocalisation_inliers) continue;
    std::vector<std::int64_t> matches(static_cast<std::size_t>(frame.size()), -1);
    // Each map point keeps the first keypoint that claims it (OneToOneRule says why not the closest).
    for (const DescriptorPair& m : match_descriptors_one_to_one(query, train, settings_.max_hamming, settings_.ratio,
                                                                OneToOneRule::first_claim)) {
      matches[static_cast<std::size_t>(query_index[static_cast<std::size_t>(m.query)])] =
          train_point[static_cast<std::size_t>(m.train)];
    }
    Eigen::Isometry3d T_ransac;
    if (!ransac_pose(frame, map, matches, settings_.min_relocalisation_inliers, T_ransac)) continue;
    Attempt local;
    // The local map around the candidate: an old place's points are not in the current one.
    if (!refine_with_local_map(frame, map, local_map_points(map, id), T_ransac, local)) continue;
    if (local.inliers < settings_.min_relocalisation_inliers) continue;
    out = std::move(local);
    return true;
  }
  return false;
}

TrackResult Tracker::track(const Frame& frame, const Map& map) {
  if (frame.size() > 0 &&
      (frame.descriptors.type() != CV_8UC1 || frame.descriptors.cols != 32 || frame.descriptors.rows != frame.size())) {
    throw std::invalid_argument("Tracker::track: frame " + std::to_string(frame.index) +
                                ": descriptors must be one 32-byte CV_8UC1 ORB row per keypoint");
  }
  TrackResult result;
  result.map_point_ids.assign(static_cast<std::size_t>(frame.size()), -1);
  if (map.keyframe_count() == 0) {
    int usable = 0;
    for (int i = 0; i < frame.size(); ++i) usable += frame.is_static(i) && frame.has_depth(i);
    if (usable < settings_.min_initial_points) return result;  // lost: not enough to start a map
    result.state = TrackingState::initialised;
    last_has_pose_ = true;
    remember_last_frame(frame);
    T_world_last_ = Eigen::Isometry3d::Identity();
    T_last_current_velocity_ = Eigen::Isometry3d::Identity();
    return result;
  }
  const Eigen::Isometry3d prediction = T_world_last_ * T_last_current_velocity_;
  Attempt attempt;
  TrackingState state = TrackingState::tracked;
  bool ok = track_local_map(frame, map, prediction, attempt);
  // The view has moved beyond the map (the keyframes lag behind a fast turn): frame-to-frame
  // odometry against the previous frame keeps the pose, and the frame becomes a keyframe.
  if (!ok && last_has_pose_ && settings_.track_last_frame) {
    attempt = Attempt{};
    ok = track_last_frame(frame, map, prediction, attempt);
    if (ok) state = TrackingState::odometry;
  }
  if (!ok) {
    ok = relocalise(frame, map, attempt);
    state = TrackingState::relocalised;
  }
  if (!ok) {
    T_last_current_velocity_ = Eigen::Isometry3d::Identity();  // the motion model is stale now
    last_has_pose_ = false;
    last_points_camera_m_.clear();
    last_descriptors_ = cv::Mat();
    return result;
  }
  remember_last_frame(frame);
  // The motion since the previous frame is known whenever that frame had a pose, relocalised or
  // not (resetting it after every relocalisation predicted a standing camera, one frame's motion
  // off, and failed again at the next frame).
  T_last_current_velocity_ =
      last_has_pose_ ? T_world_last_.inverse() * attempt.T_world_camera : Eigen::Isometry3d::Identity();
  last_has_pose_ = true;
  T_world_last_ = attempt.T_world_camera;
  result.state = state;
  result.T_world_camera = attempt.T_world_camera;
  result.matches = attempt.matches;
  result.inliers = attempt.inliers;
  result.map_point_ids = std::move(attempt.map_point_ids);
  result.visible_map_points = std::move(attempt.visible);

  // The reference keyframe: the one observing most of the tracked points (ties: smaller id).
  std::vector<int> votes(static_cast<std::size_t>(map.keyframe_count()), 0);
  for (const std::int64_t p : result.map_point_ids) {
    if (p < 0) continue;
    for (const Observation& o : map.map_point(p).observations) ++votes[static_cast<std::size_t>(o.keyframe_id)];
  }
  const auto best = std::max_element(votes.begin(), votes.end());
  if (best != votes.end() && *best > 0) reference_keyframe_ = static_cast<int>(best - votes.begin());
  result.reference_keyframe = reference_keyframe_;
  return result;
}

}  // namespace slam
}  // namespace cge
