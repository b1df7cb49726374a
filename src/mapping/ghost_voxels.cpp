#include "cge/mapping/ghost_voxels.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/dataset/tum_sequence.hpp"
#include "cge/voxels/semantic_integrity.hpp"

namespace cge {
namespace mapping {

namespace {

namespace fs = std::filesystem;

/// Ids of moving instances from the mask folder's instances.csv (id,class_id,class_name,moving).
std::set<std::uint16_t> moving_ids(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::invalid_argument("ghost voxels: cannot read " + csv.string());
  std::set<std::uint16_t> ids;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#' || (line_number == 1 && line.rfind("id", 0) == 0)) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
    const std::string where = csv.string() + ":" + std::to_string(line_number);
    if (fields.size() != 4) throw std::invalid_argument("ghost voxels: " + where + ": expected 4 fields");
    try {
      std::size_t used = 0;
      const int id = std::stoi(fields[0], &used);
      if (used != fields[0].size() || id < 1 || id > 65535) throw std::invalid_argument("id");
      if (fields[3] != "0" && fields[3] != "1") throw std::invalid_argument("moving");
      if (fields[3] == "1") ids.insert(static_cast<std::uint16_t>(id));
    } catch (const std::exception&) {
      throw std::invalid_argument("ghost voxels: " + where + ": malformed id or moving field");
    }
  }
  return ids;
}

/// Sorts `v` by voxel_less (unless it already is) and removes repeats.
void sort_unique(std::vector<VoxelIndex>& v) {
  if (!std::is_sorted(v.begin(), v.end(), voxel_less)) std::sort(v.begin(), v.end(), voxel_less);
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// Sorts and deduplicates `fresh`, then merges it into the sorted unique `into`.
void merge_unique(std::vector<VoxelIndex>& into, std::vector<VoxelIndex>& fresh) {
  sort_unique(fresh);
  std::vector<VoxelIndex> merged;
  merged.reserve(into.size() + fresh.size());
  std::set_union(into.begin(), into.end(), fresh.begin(), fresh.end(), std::back_inserter(merged), voxel_less);
  into.swap(merged);
  fresh.clear();
}

/// Index of the first of the ascending `times` within max_difference_s of t_s, or -1.
int first_within(const std::vector<double>& times, double t_s, double max_difference_s) {
  const auto it = std::lower_bound(times.begin(), times.end(), t_s - max_difference_s);
  if (it == times.end() || std::abs(*it - t_s) > max_difference_s) return -1;
  return static_cast<int>(it - times.begin());
}

}  // namespace

GhostVoxels ghost_voxels_from_sequence(const fs::path& folder, double resolution_m,
                                       const GhostVoxelSettings& settings) {
  if (settings.pixel_stride < 1) throw std::invalid_argument("GhostVoxelSettings.pixel_stride must be >= 1");
  if (!(resolution_m > 0 && std::isfinite(resolution_m)))
    throw std::invalid_argument("ghost voxels: resolution must be finite and > 0");
  const dataset::TumSequence sequence(folder);
  if (!sequence.masks_folder())
    throw std::invalid_argument("ghost voxels: " + (folder / "masks").string() + " is missing");
  if (!sequence.camera_settings_file())
    throw std::invalid_argument("ghost voxels: " + (folder / "camera.yaml").string() + " is missing");
  const bool own_poses = !settings.frame_poses.empty();
  if (!own_poses && !sequence.has_ground_truth())
    throw std::invalid_argument("ghost voxels: " + (folder / "groundtruth.txt").string() + " is missing or empty");
  for (const metrics::StampedPose& p : settings.frame_poses) {
    if (!p.T_world_camera.matrix().allFinite() || !std::isfinite(p.timestamp_s)) {
      throw std::invalid_argument("ghost voxels: the frame pose at " + std::to_string(p.timestamp_s) +
                                  " s is not finite");
    }
  }
  const fs::path masks = *sequence.masks_folder();
  const std::set<std::uint16_t> moving = moving_ids(masks / "instances.csv");
  const dataset::OrbSlam2Settings camera = dataset::read_orbslam2_settings(*sequence.camera_settings_file());
  const float fx = static_cast<float>(camera.camera.fx_px), fy = static_cast<float>(camera.camera.fy_px);
  const float cx = static_cast<float>(camera.camera.cx_px), cy = static_cast<float>(camera.camera.cy_px);
  const auto& truth = sequence.ground_truth();

  GhostVoxels out;
  out.resolution_m = resolution_m;
  // The frames to use and their poses in the map's frame: (frame index, T_map_camera).
  std::vector<std::pair<int, Eigen::Isometry3d>> used;
  if (own_poses) {
    std::vector<double> frame_times;  // ascending: the sequence lists its frames in time order
    for (int i = 0; i < sequence.frame_count(); ++i) frame_times.push_back(sequence.timestamp_s(i));
    for (const metrics::StampedPose& p : settings.frame_poses) {
      const int match = first_within(frame_times, p.timestamp_s, settings.max_time_difference_s);
      if (match < 0) {
        throw std::invalid_argument("ghost voxels: the frame pose at " + std::to_string(p.timestamp_s) +
                                    " s matches no frame of " + folder.string());
      }
      used.emplace_back(match, p.T_world_camera);
    }
  } else {
    std::vector<double> truth_times;
    for (const dataset::GroundTruthPose& p : truth) truth_times.push_back(p.timestamp_s);
    for (int i = 0; i < sequence.frame_count(); ++i) {
      const int pose = first_within(truth_times, sequence.timestamp_s(i), settings.max_time_difference_s);
      if (pose < 0) {
        throw std::invalid_argument("ghost voxels: no ground-truth pose for frame " +
                                    sequence.files(i).rgb_path.stem().string() + " in " +
                                    (folder / "groundtruth.txt").string());
      }
      used.emplace_back(i, settings.T_map_world * truth[static_cast<std::size_t>(pose)].T_world_camera);
    }
  }
  std::vector<VoxelIndex> person, still, fresh_person, fresh_still;
  for (const auto& [frame_index, T_map_camera] : used) {
    const dataset::TumFrame frame = sequence.load(frame_index);
    const fs::path mask_path = masks / (frame.rgb_stem + ".png");
    const cv::Mat labels = cv::imread(mask_path.string(), cv::IMREAD_UNCHANGED);
    if (labels.empty() || labels.type() != CV_16UC1 || labels.size() != frame.depth.size()) {
      throw std::invalid_argument("ghost voxels: " + mask_path.string() +
                                  " is missing or not a 16-bit label image of the depth image's size");
    }
    const cv::Mat depth = frame.depth_metres();
    const Eigen::Matrix3f R = T_map_camera.linear().cast<float>();
    const Eigen::Vector3f t = T_map_camera.translation().cast<float>();
    for (int v = 0; v < depth.rows; v += settings.pixel_stride) {
      const float* d = depth.ptr<float>(v);
      const std::uint16_t* l = labels.ptr<std::uint16_t>(v);
      for (int u = 0; u < depth.cols; u += settings.pixel_stride) {
        const float z = d[u];
        if (!(z > 0)) continue;
        const Eigen::Vector3f p_camera((static_cast<float>(u) - cx) * z / fx, (static_cast<float>(v) - cy) * z / fy, z);
        const VoxelIndex index = voxel_of(R * p_camera + t, resolution_m);
        (moving.count(l[u]) ? fresh_person : fresh_still).push_back(index);
      }
    }
    merge_unique(person, fresh_person);
    merge_unique(still, fresh_still);
    ++out.frames;
  }
  out.person_voxels = person.size();
  out.static_voxels = still.size();
  out.ghost = ghost_set(std::move(person), std::move(still));
  return out;
}

std::vector<VoxelIndex> ghost_set(std::vector<VoxelIndex> person, std::vector<VoxelIndex> still) {
  sort_unique(person);  // the sequence's sets arrive sorted and unique: a linear check then
  sort_unique(still);
  std::vector<VoxelIndex> ghost;
  std::set_difference(person.begin(), person.end(), still.begin(), still.end(), std::back_inserter(ghost), voxel_less);
  return ghost;
}

double ghost_fraction(const OccupiedVoxels& map, const GhostVoxels& ghosts) {
  if (std::abs(map.resolution_m - ghosts.resolution_m) > 1e-9) {
    throw std::invalid_argument("ghost_fraction: map resolution " + std::to_string(map.resolution_m) +
                                " m differs from the ghost set's " + std::to_string(ghosts.resolution_m) + " m");
  }
  return ghost_fraction(map, ghosts.ghost);
}

}  // namespace mapping
}  // namespace cge
