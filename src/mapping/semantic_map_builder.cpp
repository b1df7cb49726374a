#include "cge/mapping/semantic_map_builder.hpp"

#include "cge/opencv/undistort.hpp"

#include <cmath>
#include <map>
#include <stdexcept>

#include "cge/voxels/ply_writer.hpp"
#include "cge/voxels/voxel_filter.hpp"

namespace cge {
namespace mapping {

void check_settings(const SemanticMapSettings& s) {
  const auto bad = [](const std::string& what) { throw std::invalid_argument("SemanticMapSettings." + what); };
  if (s.pixel_stride < 1) bad("pixel_stride must be >= 1");
  if (s.octree_pixel_stride < 1 || s.octree_pixel_stride % s.pixel_stride != 0)
    bad("octree_pixel_stride must be a positive multiple of pixel_stride");
  if (!(s.max_range_m > 0 && std::isfinite(s.max_range_m))) bad("max_range_m must be finite and > 0");
  if (!(s.cloud_voxel_m > 0 && std::isfinite(s.cloud_voxel_m))) bad("cloud_voxel_m must be finite and > 0");
  if (s.min_entity_points < 1) bad("min_entity_points must be >= 1");
  check_settings(s.dynamic_region);
  octomap_adapter::check_settings(s.octree);
}

namespace {

void check_image(const cv::Mat& m, int type, const cv::Size& size, const slam::Keyframe& kf, const char* name) {
  if (m.type() != type || m.size() != size) {
    throw std::invalid_argument("SemanticMapBuilder: keyframe " + std::to_string(kf.id) + ": " + name + " must be " +
                                std::to_string(size.width) + " x " + std::to_string(size.height) + " of type " +
                                std::to_string(type) + " (got " + std::to_string(m.cols) + " x " +
                                std::to_string(m.rows) + " of type " + std::to_string(m.type()) + ")");
  }
}

}  // namespace

SemanticMapBuilder::SemanticMapBuilder(const PinholeIntrinsics<double>& intrinsics, const SemanticMapSettings& settings,
                                       const LensDistortion& distortion)
    : intrinsics_(intrinsics),
      distortion_(distortion),
      settings_(settings),
      octree_((check_settings(settings), settings.octree)) {
  if (!distortion.is_finite()) throw std::invalid_argument("SemanticMapBuilder: distortion coefficients must be finite");
  if (!(std::isfinite(intrinsics.fx_px) && intrinsics.fx_px > 0 && std::isfinite(intrinsics.fy_px) &&
        intrinsics.fy_px > 0 && std::isfinite(intrinsics.cx_px) && std::isfinite(intrinsics.cy_px))) {
    throw std::invalid_argument("SemanticMapBuilder: intrinsics must be finite with fx, fy > 0");
  }
}

const cv::Mat& SemanticMapBuilder::undistorted_rays(cv::Size size) const {
  if (rays_.size() == size) return rays_;
  std::vector<cv::Point2f> pixels;
  pixels.reserve(static_cast<std::size_t>(size.area()));
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) pixels.emplace_back(static_cast<float>(u), static_cast<float>(v));
  }
  const std::vector<cv::Point2f> ideal = opencv::undistort_pixels(pixels, intrinsics_, distortion_);
  rays_.create(size, CV_32FC2);
  for (int v = 0; v < size.height; ++v) {
    auto* row = rays_.ptr<cv::Vec2f>(v);
    for (int u = 0; u < size.width; ++u) {
      const cv::Point2f& p = ideal[static_cast<std::size_t>(v * size.width + u)];
      row[u] = cv::Vec2f(static_cast<float>((p.x - intrinsics_.cx_px) / intrinsics_.fx_px),
                         static_cast<float>((p.y - intrinsics_.cy_px) / intrinsics_.fy_px));
    }
  }
  return rays_;
}

std::vector<SemanticPoint> SemanticMapBuilder::keyframe_points(const slam::Keyframe& kf, bool octree_grid) const {
  std::vector<SemanticPoint> points;
  back_project(kf, octree_grid ? settings_.octree_pixel_stride : settings_.pixel_stride, points, nullptr, nullptr);
  return points;
}

void SemanticMapBuilder::back_project(const slam::Keyframe& kf, int stride, std::vector<SemanticPoint>& points,
                                      std::vector<Eigen::Vector3f>* octree_positions,
                                      std::vector<std::uint16_t>* octree_labels) const {
  if (kf.depth_m.empty()) {
    throw std::invalid_argument("SemanticMapBuilder: keyframe " + std::to_string(kf.id) + " has no depth_m image");
  }
  const cv::Size size = kf.depth_m.size();
  check_image(kf.depth_m, CV_32FC1, size, kf, "depth_m");
  const bool has_labels = !kf.class_labels.empty();
  const bool has_mask = settings_.use_dynamic_mask && !kf.dynamic_mask.empty();
  const bool has_bgr = !kf.bgr.empty();
  if (has_labels) check_image(kf.class_labels, CV_16UC1, size, kf, "class_labels");
  if (has_mask) check_image(kf.dynamic_mask, CV_8UC1, size, kf, "dynamic_mask");
  if (has_bgr) check_image(kf.bgr, CV_8UC3, size, kf, "bgr");
  if (settings_.colour_unlabelled_from_image && !has_bgr) {
    throw std::invalid_argument("SemanticMapBuilder: keyframe " + std::to_string(kf.id) +
                                " has no bgr image but colour_unlabelled_from_image is set");
  }
  if (!kf.T_world_camera.matrix().allFinite()) {
    throw std::invalid_argument("SemanticMapBuilder: keyframe " + std::to_string(kf.id) + " pose is not finite");
  }
  const Eigen::Matrix3f R = kf.T_world_camera.linear().cast<float>();
  const Eigen::Vector3f t = kf.T_world_camera.translation().cast<float>();
  const float fx = static_cast<float>(intrinsics_.fx_px), fy = static_cast<float>(intrinsics_.fy_px);
  const float cx = static_cast<float>(intrinsics_.cx_px), cy = static_cast<float>(intrinsics_.cy_px);
  const float max_range = static_cast<float>(settings_.max_range_m);
  const cv::Mat* rays = distortion_.is_zero() ? nullptr : &undistorted_rays(size);
  const cv::Mat leave_out = !has_mask ? cv::Mat()
                            : settings_.grow_dynamic_mask
                                ? dynamic_region(kf.dynamic_mask, kf.depth_m, settings_.dynamic_region)
                                : kf.dynamic_mask;

  points.clear();
  points.reserve(static_cast<std::size_t>((size.height + stride - 1) / stride) *
                 static_cast<std::size_t>((size.width + stride - 1) / stride));
  const int octree_stride = settings_.octree_pixel_stride;  // a multiple of stride when octree_positions is set
  for (int v = 0; v < size.height; v += stride) {
    const float* depth = kf.depth_m.ptr<float>(v);
    const std::uint16_t* labels = has_labels ? kf.class_labels.ptr<std::uint16_t>(v) : nullptr;
    const std::uint8_t* mask = has_mask ? leave_out.ptr<std::uint8_t>(v) : nullptr;
    const cv::Vec3b* bgr = has_bgr ? kf.bgr.ptr<cv::Vec3b>(v) : nullptr;
    const cv::Vec2f* ray = rays ? rays->ptr<cv::Vec2f>(v) : nullptr;
    for (int u = 0; u < size.width; u += stride) {
      const float z = depth[u];
      if (!(z > 0 && z <= max_range)) continue;  // also drops NaN
      if (mask && mask[u] != 0) continue;
      const Eigen::Vector3f p_camera = ray ? Eigen::Vector3f(ray[u][0] * z, ray[u][1] * z, z)
                                           : Eigen::Vector3f((static_cast<float>(u) - cx) * z / fx,
                                                             (static_cast<float>(v) - cy) * z / fy, z);
      SemanticPoint p;
      p.position_m = R * p_camera + t;
      p.class_label = labels ? labels[u] : std::uint16_t(0);
      if (!preset_colour_of_label(p.class_label, p.colour)) {
        p.colour = settings_.colour_unlabelled_from_image ? Rgb8{bgr[u][2], bgr[u][1], bgr[u][0]} : kOtherClassColour;
      }
      points.push_back(p);
      if (octree_positions && v % octree_stride == 0 && u % octree_stride == 0) {
        octree_positions->push_back(p.position_m);
        octree_labels->push_back(p.class_label);
      }
    }
  }
}

void SemanticMapBuilder::insert(const slam::Keyframe& kf) {
  // One pass: the cloud's points (pixel_stride) and among them the octree's (octree_pixel_stride).
  std::vector<SemanticPoint> points;
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::uint16_t> labels;
  back_project(kf, settings_.pixel_stride, points, &positions, &labels);

  // Entities: per class label present, the voxel box (octree resolution) of its points.
  struct Box {
    VoxelIndex lo, hi;
    int count = 0;
  };
  std::map<std::uint16_t, Box> boxes;
  for (const SemanticPoint& p : points) {
    Rgb8 preset;
    if (!preset_colour_of_label(p.class_label, preset)) continue;  // the octree keeps no class for it
    const VoxelIndex i = voxel_of(p.position_m, settings_.octree.resolution_m);
    auto it = boxes.find(p.class_label);
    if (it == boxes.end()) {
      boxes[p.class_label] = Box{i, i, 1};
    } else {
      it->second.lo = it->second.lo.cwiseMin(i);
      it->second.hi = it->second.hi.cwiseMax(i);
      ++it->second.count;
    }
  }
  for (const auto& b : boxes) {
    if (b.second.count < settings_.min_entity_points) continue;
    entities_.push_back(IntegrityEntity{b.first, b.second.lo, b.second.hi});
  }

  octree_.insert_scan(kf.T_world_camera.translation(), positions, labels);
  const std::vector<SemanticPoint> filtered = voxel_filter(points, settings_.cloud_voxel_m);
  filtered_points_.insert(filtered_points_.end(), filtered.begin(), filtered.end());
  ++keyframes_;
}

void SemanticMapBuilder::clear() {
  octree_.clear();
  filtered_points_.clear();
  entities_.clear();
  keyframes_ = 0;
}

void SemanticMapBuilder::rebuild(const std::vector<slam::Keyframe>& keyframes) {
  clear();
  for (const slam::Keyframe& kf : keyframes) insert(kf);
}

std::vector<SemanticPoint> SemanticMapBuilder::cloud() const {
  return voxel_filter(filtered_points_, settings_.cloud_voxel_m);
}

void SemanticMapBuilder::write_ply(const std::filesystem::path& path, bool overwrite) const {
  mapping::write_ply(path, cloud(), overwrite);
}

void SemanticMapBuilder::write_octree(const std::filesystem::path& path_ot, const std::filesystem::path& path_bt,
                                      bool overwrite) {
  // Check both before writing either, so a refusal leaves nothing half done.
  if (!overwrite && (std::filesystem::exists(path_ot) || std::filesystem::exists(path_bt))) {
    throw std::invalid_argument(
        "SemanticMapBuilder::write_octree: " + (std::filesystem::exists(path_ot) ? path_ot : path_bt).string() +
        " exists (not overwritten)");
  }
  octree_.write_ot(path_ot, overwrite);
  octree_.write_bt(path_bt, overwrite);
}

MapFigures SemanticMapBuilder::scores() const {
  MapFigures f;
  f.keyframes = keyframes_;
  f.cloud_points = cloud().size();
  const OccupiedVoxels voxels = occupied_voxels();
  f.occupied_voxels = voxels.voxels.size();
  const IntegrityScores s = integrity_scores(voxels, entities_);
  f.integrity = s.integrity;
  f.fluctuation = s.fluctuation;
  f.entities = s.entities;
  f.octree_memory_bytes = octree_.memory_bytes();
  return f;
}

}  // namespace mapping
}  // namespace cge
