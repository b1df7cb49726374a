#pragma once
// SemanticOctree: an OctoMap ColorOcTree with log-odds occupancy from camera scans and one class
// per occupied voxel (ALGORITHMS.md section 8). OctoMap + core only.
//
// Each scan is a set of world points seen from one camera origin, integrated as OctoMap's
// insertPointCloud(discretize) does, with OctoMap's ray caster (computeRayKeys) and updateNode:
// voxels on the rays from the origin get a miss, the voxels of the points (within max range) a hit,
// L(n | z_1:t+1) = L(n | z_1:t) + L(n | z_t+1), clamped; a cell is updated once per scan, hits win.
// To save time, free space is carved by one ray per block of ray_block_voxels^3 end voxels.
// Each end voxel also counts votes for the class labels of the points in it; the node's colour is
// the preset colour of the label with the most votes over all scans so far (ties: the smaller
// label), so the class can be read back from the colour (class_label_of_colour). Colours are set,
// never averaged: the tree is updated lazily and never pruned here, because OctoMap's pruning of a
// ColorOcTree averages children's colours.
//
// Determinism: no threads; OctoMap updates each node at most once per scan, so the order in which it
// walks its hash sets does not change the values; votes live in an ordered map. Same scans, same
// bytes in .ot and .bt.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <Eigen/Core>

#include "cge/mapping/class_palette.hpp"
#include "cge/mapping/map_voxel.hpp"

namespace cge {
namespace octomap_adapter {

struct SemanticOctreeSettings {
  double resolution_m = 0.05;        ///< voxel side, metres, > 0
  double max_range_m = 4.0;          ///< rays are cut at this range (no hit beyond), metres, > 0
  double probability_hit = 0.7;      ///< occupancy probability of a hit, in (0.5, 1)
  double probability_miss = 0.4;     ///< occupancy probability of a miss, in (0, 0.5)
  double clamping_min = 0.1192;      ///< lower clamp of the occupancy probability (OctoMap default)
  double clamping_max = 0.971;       ///< upper clamp of the occupancy probability (OctoMap default)
  double occupancy_threshold = 0.5;  ///< a voxel above this probability is occupied
  /// Free space: one ray per block of n x n x n end voxels (to the first end voxel of the block in
  /// key order) instead of one per end voxel. 1 = every end voxel (OctoMap's insertPointCloud with
  /// discretize); 2 casts about 4 times fewer rays on surfaces, leaving some free voxels next to
  /// surfaces unknown. Every end voxel still gets its hit. >= 1.
  int ray_block_voxels = 2;
};

/// Throws std::invalid_argument naming the first setting out of range.
inline void check_settings(const SemanticOctreeSettings& s) {
  const auto bad = [](const std::string& what) { throw std::invalid_argument("SemanticOctreeSettings." + what); };
  if (!(s.resolution_m > 0 && s.resolution_m < 1e3)) bad("resolution_m must be in (0, 1000) metres");
  if (!(s.max_range_m > 0)) bad("max_range_m must be > 0");
  if (!(s.probability_hit > 0.5 && s.probability_hit < 1)) bad("probability_hit must be in (0.5, 1)");
  if (!(s.probability_miss > 0 && s.probability_miss < 0.5)) bad("probability_miss must be in (0, 0.5)");
  if (!(s.clamping_min > 0 && s.clamping_min < s.occupancy_threshold)) bad("clamping_min must be in (0, threshold)");
  if (!(s.clamping_max < 1 && s.clamping_max > s.occupancy_threshold)) bad("clamping_max must be in (threshold, 1)");
  if (s.ray_block_voxels < 1 || s.ray_block_voxels > 1024) bad("ray_block_voxels must be in 1 .. 1024");
}

/// Occupied voxels of any ColorOcTree (one read from a file included), leaves coarser than the
/// finest level expanded to their finest voxels; sorted by voxel_less.
inline mapping::OccupiedVoxels occupied_voxels(const octomap::ColorOcTree& tree) {
  mapping::OccupiedVoxels out;
  out.resolution_m = tree.getResolution();
  const int max_depth = static_cast<int>(tree.getTreeDepth());
  const int offset = 1 << (max_depth - 1);  // key of coordinate 0 (OctoMap's tree_max_val)
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const octomap::ColorOcTreeNode::Color c = it->getColor();
    mapping::MapVoxel v;
    v.colour = mapping::Rgb8{c.r, c.g, c.b};
    v.class_label = mapping::class_label_of_colour(v.colour);
    const int size = 1 << (max_depth - static_cast<int>(it.getDepth()));
    const octomap::OcTreeKey key = it.getKey();
    const mapping::VoxelIndex first(static_cast<int>(key[0]) - size / 2 - offset,
                                    static_cast<int>(key[1]) - size / 2 - offset,
                                    static_cast<int>(key[2]) - size / 2 - offset);
    for (int dx = 0; dx < size; ++dx)
      for (int dy = 0; dy < size; ++dy)
        for (int dz = 0; dz < size; ++dz) {
          v.index = first + mapping::VoxelIndex(dx, dy, dz);
          out.voxels.push_back(v);
        }
  }
  std::sort(out.voxels.begin(), out.voxels.end(), [](const mapping::MapVoxel& a, const mapping::MapVoxel& b) {
    return mapping::voxel_less(a.index, b.index);
  });
  return out;
}

/// Reads a .ot file holding a ColorOcTree with OctoMap's own reader. Throws std::invalid_argument
/// naming the file when it cannot be read or holds another tree type.
inline std::unique_ptr<octomap::ColorOcTree> read_color_octree(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw std::invalid_argument("read_color_octree: " + path.string() + " is not a readable file");
  }
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(path.string()));
  if (!tree) throw std::invalid_argument("read_color_octree: " + path.string() + " is not an OctoMap .ot file");
  auto* colour = dynamic_cast<octomap::ColorOcTree*>(tree.get());
  if (!colour) {
    throw std::invalid_argument("read_color_octree: " + path.string() + " holds a " + tree->getTreeType() +
                                ", not a ColorOcTree");
  }
  tree.release();
  return std::unique_ptr<octomap::ColorOcTree>(colour);
}

class SemanticOctree {
 public:
  explicit SemanticOctree(const SemanticOctreeSettings& settings = {})
      : settings_(settings), tree_(make_tree(settings)) {}

  const SemanticOctreeSettings& settings() const { return settings_; }

  /// Removes everything (before a rebuild with corrected poses).
  void clear() {
    tree_ = make_tree(settings_);
    votes_.clear();
    inner_stale_ = false;
  }

  /// Integrates one scan: points_world[i] seen from origin_world, with class label labels[i]
  /// (COCO id + 1, 0 none). Throws std::invalid_argument when the sizes differ or a value is not finite.
  void insert_scan(const Eigen::Vector3d& origin_world, const std::vector<Eigen::Vector3f>& points_world,
                   const std::vector<std::uint16_t>& labels) {
    if (points_world.size() != labels.size()) {
      throw std::invalid_argument("SemanticOctree::insert_scan: " + std::to_string(points_world.size()) +
                                  " points but " + std::to_string(labels.size()) + " labels");
    }
    if (!origin_world.allFinite()) throw std::invalid_argument("SemanticOctree::insert_scan: origin not finite");
    const octomap::point3d origin(static_cast<float>(origin_world.x()), static_cast<float>(origin_world.y()),
                                  static_cast<float>(origin_world.z()));
    std::vector<std::pair<std::uint64_t, std::uint16_t>> keyed;  // (packed end key, label) of hits
    keyed.reserve(points_world.size());
    std::vector<std::uint64_t> far_ends;  // packed keys of the truncated ends of rays beyond max range
    const double max_range = settings_.max_range_m;
    for (std::size_t i = 0; i < points_world.size(); ++i) {
      const Eigen::Vector3f& p = points_world[i];
      if (!p.allFinite()) {
        throw std::invalid_argument("SemanticOctree::insert_scan: point " + std::to_string(i) + " not finite");
      }
      octomap::point3d end(p.x(), p.y(), p.z());
      const double range = (end - origin).norm();
      octomap::OcTreeKey key;
      if (range <= max_range) {
        if (tree_->coordToKeyChecked(end, key)) keyed.emplace_back(pack(key), labels[i]);
      } else {
        end = origin + (end - origin) * static_cast<float>(max_range / range);
        if (tree_->coordToKeyChecked(end, key)) far_ends.push_back(pack(key));
      }
    }
    std::sort(keyed.begin(), keyed.end());
    std::sort(far_ends.begin(), far_ends.end());
    far_ends.erase(std::unique(far_ends.begin(), far_ends.end()), far_ends.end());

    // Free cells: rays to one end voxel per block (hits and truncated ends alike).
    octomap::KeySet free_cells;
    octomap::KeyRay ray;
    std::uint64_t last_block = ~std::uint64_t(0);
    const auto cast_to = [&](std::uint64_t packed_key) {
      const std::uint64_t block = block_of(packed_key);
      if (block == last_block) return;
      last_block = block;
      if (tree_->computeRayKeys(origin, tree_->keyToCoord(unpack(packed_key)), ray)) {
        free_cells.insert(ray.begin(), ray.end());
      }
    };
    std::vector<std::uint64_t> ends;
    ends.reserve(keyed.size() + far_ends.size());
    for (std::size_t i = 0; i < keyed.size(); ++i) {
      if (i == 0 || keyed[i].first != keyed[i - 1].first) ends.push_back(keyed[i].first);
    }
    const std::size_t hit_count = ends.size();
    ends.insert(ends.end(), far_ends.begin(), far_ends.end());
    std::vector<std::pair<std::uint64_t, std::uint64_t>> by_block(ends.size());  // (block, key): first key per block
    for (std::size_t i = 0; i < ends.size(); ++i) by_block[i] = {block_of(ends[i]), ends[i]};
    std::sort(by_block.begin(), by_block.end());
    for (const auto& bk : by_block) cast_to(bk.second);

    // Log-odds updates: each cell once per scan, hits win over misses; the hits below, with the votes.
    for (std::size_t i = 0; i < hit_count; ++i) free_cells.erase(unpack(ends[i]));
    for (const octomap::OcTreeKey& k : free_cells) tree_->updateNode(k, false, /*lazy_eval=*/true);
    inner_stale_ = true;

    for (std::size_t i = 0; i < keyed.size();) {
      const std::uint64_t key = keyed[i].first;
      std::vector<std::pair<std::uint16_t, std::uint32_t>>& votes = votes_[key];
      std::size_t j = i;
      while (j < keyed.size() && keyed[j].first == key) {
        const std::uint16_t label = keyed[j].second;
        std::uint32_t n = 0;
        for (; j < keyed.size() && keyed[j].first == key && keyed[j].second == label; ++j) ++n;
        const auto v = std::find_if(votes.begin(), votes.end(), [label](const auto& e) { return e.first == label; });
        if (v == votes.end()) {
          votes.emplace_back(label, n);
        } else {
          v->second += n;
        }
      }
      std::uint16_t best = votes.front().first;
      std::uint32_t best_count = 0;
      for (const auto& v : votes) {
        if (v.second > best_count || (v.second == best_count && v.first < best)) {
          best = v.first;
          best_count = v.second;
        }
      }
      if (octomap::ColorOcTreeNode* node = tree_->updateNode(unpack(key), true, /*lazy_eval=*/true)) {
        const mapping::Rgb8 c = mapping::class_colour(best);
        node->setColor(c.r, c.g, c.b);
      }
      i = j;
    }
  }

  /// The occupied voxels with their colours and classes.
  mapping::OccupiedVoxels occupied_voxels() const { return octomap_adapter::occupied_voxels(*tree_); }

  /// OctoMap's memoryUsage() of the tree plus the class votes, bytes.
  std::size_t memory_bytes() const {
    std::size_t votes = 0;
    for (const auto& v : votes_) votes += sizeof(v) + 3 * sizeof(void*) + v.second.capacity() * sizeof(v.second[0]);
    return tree_->memoryUsage() + votes;
  }
  std::size_t tree_memory_bytes() const { return tree_->memoryUsage(); }

  /// The ColorOcTree (.ot, opened by octovis). Throws std::invalid_argument when the file exists and
  /// !overwrite, std::runtime_error naming it when it cannot be written.
  void write_ot(const std::filesystem::path& path, bool overwrite = false) {
    refuse_existing(path, overwrite);
    update_inner();
    if (!tree_->write(path.string())) throw std::runtime_error("SemanticOctree: cannot write " + path.string());
  }

  /// Occupancy only (.bt, an OcTree in OctoMap's binary format: free / occupied / unknown).
  void write_bt(const std::filesystem::path& path, bool overwrite = false) {
    refuse_existing(path, overwrite);
    octomap::OcTree plain(settings_.resolution_m);
    apply_probabilities(plain, settings_);
    for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
      plain.setNodeValue(it.getKey(), it->getLogOdds(), /*lazy_eval=*/true);
    }
    plain.updateInnerOccupancy();
    if (!plain.writeBinary(path.string())) throw std::runtime_error("SemanticOctree: cannot write " + path.string());
  }

  /// The tree (inner nodes brought up to date first).
  const octomap::ColorOcTree& tree() {
    update_inner();
    return *tree_;
  }

 private:
  template <typename Tree>
  static void apply_probabilities(Tree& t, const SemanticOctreeSettings& s) {
    t.setProbHit(s.probability_hit);
    t.setProbMiss(s.probability_miss);
    t.setClampingThresMin(s.clamping_min);
    t.setClampingThresMax(s.clamping_max);
    t.setOccupancyThres(s.occupancy_threshold);
  }
  static std::unique_ptr<octomap::ColorOcTree> make_tree(const SemanticOctreeSettings& s) {
    check_settings(s);
    auto t = std::make_unique<octomap::ColorOcTree>(s.resolution_m);
    apply_probabilities(*t, s);
    return t;
  }
  static std::uint64_t pack(const octomap::OcTreeKey& k) {
    return (std::uint64_t(k[0]) << 32) | (std::uint64_t(k[1]) << 16) | std::uint64_t(k[2]);
  }
  /// The ray block of a packed key (its three 16-bit fields divided by ray_block_voxels), packed alike.
  std::uint64_t block_of(std::uint64_t p) const {
    const std::uint64_t n = static_cast<std::uint64_t>(settings_.ray_block_voxels);
    return (((p >> 32) & 0xffffu) / n << 32) | (((p >> 16) & 0xffffu) / n << 16) | ((p & 0xffffu) / n);
  }
  static octomap::OcTreeKey unpack(std::uint64_t p) {
    return octomap::OcTreeKey(static_cast<octomap::key_type>((p >> 32) & 0xffffu),
                              static_cast<octomap::key_type>((p >> 16) & 0xffffu),
                              static_cast<octomap::key_type>(p & 0xffffu));
  }
  static void refuse_existing(const std::filesystem::path& path, bool overwrite) {
    if (!overwrite && std::filesystem::exists(path)) {
      throw std::invalid_argument("SemanticOctree: " + path.string() + " exists (not overwritten)");
    }
  }
  void update_inner() {
    if (inner_stale_) tree_->updateInnerOccupancy();
    inner_stale_ = false;
  }

  SemanticOctreeSettings settings_;
  std::unique_ptr<octomap::ColorOcTree> tree_;
  /// Per end voxel (packed key, ordered): (label, points) pairs, in first-seen order.
  std::map<std::uint64_t, std::vector<std::pair<std::uint16_t, std::uint32_t>>> votes_;
  bool inner_stale_ = false;
};

}  // namespace octomap_adapter
}  // namespace cge
