#pragma once
// SemanticOctree: an OctoMap ColorOcTree with log-odds occupancy from camera scans and one class
// per occupied voxel (docs/METHOD.md section 8). OctoMap + core only.
//
// Each scan is a set of world points seen from one camera origin, integrated as OctoMap's
// insertPointCloud(discretize) does, with OctoMap's ray caster (computeRayKeys) and its updateNode
// rule (applied in one depth-first walk over the scan's cells in Morton order, see update_leaves):
// voxels on the rays from the origin get a miss, the voxels of the points (within max range) a hit,
// L(n | z_1:t+1) = L(n | z_1:t) + L(n | z_t+1), clamped; a cell is updated once per scan, hits win.
// Optionally (ray_block_voxels > 1) free space is carved by one ray per block of end voxels only.
// Each end voxel also counts votes for the class labels of the points in it; the node's colour is
// the preset colour of the label with the most votes over all scans so far (ties: the smaller
// label), so the class can be read back from the colour (class_label_of_colour). Colours are set,
// never averaged: the tree is updated lazily and never pruned here, because OctoMap's pruning of a
// ColorOcTree averages children's colours.
//
// Determinism: no threads; each node is updated at most once per scan, cells and votes are kept in
// sorted vectors. Same scans, same bytes in .ot and .bt.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <Eigen/Core>

#include "cge/io/stderr_capture.hpp"
#include "cge/voxels/class_palette.hpp"
#include "cge/voxels/map_voxel.hpp"

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
  /// discretize); 2 casts about 4 times fewer rays on surfaces but leaves voxels next to surfaces
  /// uncarved: on walking_xyz a person's lower body from a frame whose instance was missed or whose
  /// feet were lost stayed occupied, no later ray crossing it (docs/MAPS.md). Every end voxel
  /// still gets its hit. >= 1.
  int ray_block_voxels = 1;
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

namespace detail {

/// OctoMap's trees are 16 levels deep below the root (OcTreeBaseImpl's tree_depth).
constexpr int kOctreeDepth = 16;
/// Bytes of one ColorOcTreeNode in a .ot stream: log-odds float, r g b, child bitmask.
constexpr std::size_t kColorNodeBytes = sizeof(float) + 3 + 1;

/// Checks the node stream of a ColorOcTree .ot file (OcTreeBaseImpl::readNodesRecurs' layout:
/// each node's data then a byte of child flags, children depth-first) before OctoMap reads it:
/// OctoMap's reader neither notices the end of a truncated file (it builds nodes from whatever it
/// reads, a wrong map or runaway allocation) nor bounds the depth. Throws std::invalid_argument
/// naming `file` unless the stream holds exactly `expected_nodes` nodes, no node lies deeper than
/// the tree, every log-odds value is finite and no byte follows the last node.
inline void check_color_octree_stream(const std::string& bytes, std::size_t begin, std::size_t expected_nodes,
                                      const std::string& file) {
  const auto fail = [&file](const std::string& what) {
    throw std::invalid_argument("read_color_octree: " + file + " is truncated or corrupt: " + what);
  };
  std::size_t pos = begin, nodes = 0;
  std::vector<std::pair<int, int>> stack;  // (depth of the node to read, nodes left at that depth)
  stack.emplace_back(0, 1);
  while (!stack.empty()) {
    if (stack.back().second == 0) {
      stack.pop_back();
      continue;
    }
    --stack.back().second;
    const int depth = stack.back().first;
    if (bytes.size() - pos < kColorNodeBytes) {
      fail("the data ends after " + std::to_string(nodes) + " of " + std::to_string(expected_nodes) + " nodes");
    }
    float log_odds = 0;
    std::memcpy(&log_odds, bytes.data() + pos, sizeof log_odds);
    if (!std::isfinite(log_odds)) fail("node " + std::to_string(nodes) + " has a log-odds value that is not finite");
    const unsigned char children = static_cast<unsigned char>(bytes[pos + kColorNodeBytes - 1]);
    pos += kColorNodeBytes;
    if (++nodes > expected_nodes) fail("it holds more nodes than the " + std::to_string(expected_nodes) + " of its header");
    if (children != 0) {
      if (depth >= kOctreeDepth) fail("node " + std::to_string(nodes - 1) + " has children below the deepest level");
      int count = 0;
      for (int bit = 0; bit < 8; ++bit) count += (children >> bit) & 1;
      stack.emplace_back(depth + 1, count);
    }
  }
  if (nodes != expected_nodes) {
    fail("it holds " + std::to_string(nodes) + " nodes, its header says " + std::to_string(expected_nodes));
  }
  if (pos != bytes.size()) fail(std::to_string(bytes.size() - pos) + " bytes follow the last node");
}

}  // namespace detail

/// Reads a .ot file holding a ColorOcTree. The header and the node stream are checked first
/// (detail::check_color_octree_stream), so that a truncated or corrupt file is refused instead of
/// read as another map; then OctoMap's own reader builds the tree. Throws std::invalid_argument
/// naming the file when it cannot be read, holds another tree type, or is truncated or corrupt.
inline std::unique_ptr<octomap::ColorOcTree> read_color_octree(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw std::invalid_argument("read_color_octree: " + file + " is a directory, not a file");
  }
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw std::invalid_argument("read_color_octree: " + file + " is not a readable file");
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.is_open() || in.bad()) throw std::invalid_argument("read_color_octree: cannot read " + file);

  // The text header (AbstractOcTree::readHeader): "# Octomap OcTree file", then "id", "size",
  // "res" lines ('#' comments allowed) up to the line "data".
  std::size_t pos = 0;
  const auto next_line = [&bytes, &pos](std::string& line) {
    if (pos >= bytes.size()) return false;
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) end = bytes.size();
    line = bytes.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = end + 1;
    return true;
  };
  const std::string not_ot = "read_color_octree: " + file + " is not an OctoMap .ot file";
  std::string line;
  if (!next_line(line) || line.compare(0, 21, "# Octomap OcTree file") != 0) throw std::invalid_argument(not_ot);
  std::string id;
  long long size = -1;
  bool data = false;
  while (!data && next_line(line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string token;
    fields >> token;
    if (token == "id") {
      fields >> id;
    } else if (token == "size") {
      if (!(fields >> size) || size < 1) throw std::invalid_argument(not_ot + " (bad 'size' line)");
    } else if (token == "data") {
      data = true;
    }
  }
  if (!data || id.empty() || size < 1) throw std::invalid_argument(not_ot + " (incomplete header)");
  if (id != "ColorOcTree") {
    throw std::invalid_argument("read_color_octree: " + file + " holds a " + id + ", not a ColorOcTree");
  }
  if (pos > bytes.size()) pos = bytes.size();
  detail::check_color_octree_stream(bytes, pos, static_cast<std::size_t>(size), file);

  std::istringstream stream(bytes);
  std::unique_ptr<octomap::AbstractOcTree> tree;
  {
    // OctoMap reports progress ("Reading octree type ...") on std::cerr; the stream was checked
    // above, so nothing it could say is news: keep it off the caller's standard error.
    std::ostringstream octomap_chatter;
    std::streambuf* const cerr_buffer = std::cerr.rdbuf(octomap_chatter.rdbuf());
    try {
      tree.reset(octomap::AbstractOcTree::read(stream));
    } catch (...) {
      std::cerr.rdbuf(cerr_buffer);
      throw;
    }
    std::cerr.rdbuf(cerr_buffer);
  }
  if (!tree) throw std::invalid_argument(not_ot);
  auto* colour = dynamic_cast<octomap::ColorOcTree*>(tree.get());
  if (!colour) {
    throw std::invalid_argument("read_color_octree: " + file + " holds a " + tree->getTreeType() +
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

    // Free cells: rays to one end voxel per block, the block's first in packed key order (hits and
    // truncated ends alike), collected as Morton codes, sorted and made unique.
    std::vector<std::uint64_t> ends;
    ends.reserve(keyed.size() + far_ends.size());
    for (std::size_t i = 0; i < keyed.size(); ++i) {
      if (i == 0 || keyed[i].first != keyed[i - 1].first) ends.push_back(keyed[i].first);
    }
    const std::size_t hit_count = ends.size();
    ends.insert(ends.end(), far_ends.begin(), far_ends.end());
    std::vector<std::pair<std::uint64_t, std::uint64_t>> by_block(ends.size());  // (block, key): first key per block
    for (std::size_t i = 0; i < ends.size(); ++i) by_block[i] = {block_of(ends[i]), ends[i]};
    // Blocks of one voxel: every end gets its ray (a repeat casts the same cells again), no sort needed.
    if (settings_.ray_block_voxels > 1) std::sort(by_block.begin(), by_block.end());
    // Rays share most cells near the camera: a bit per cell of the cube of keys around the origin
    // that max range can reach drops repeats before the sort (cells outside it are kept and
    // deduplicated by the sort).
    free_codes_.clear();
    const SeenCube cube = seen_cube(origin);
    for (std::size_t i = 0; i < by_block.size(); ++i) {
      if (i > 0 && by_block[i].first == by_block[i - 1].first) continue;
      if (tree_->computeRayKeys(origin, tree_->keyToCoord(unpack(by_block[i].second)), ray_)) {
        for (const octomap::OcTreeKey& k : ray_) {
          if (cube.side > 0) {
            const std::int64_t a = static_cast<std::int64_t>(k[0]) - cube.first[0];
            const std::int64_t b = static_cast<std::int64_t>(k[1]) - cube.first[1];
            const std::int64_t c = static_cast<std::int64_t>(k[2]) - cube.first[2];
            if (a >= 0 && b >= 0 && c >= 0 && a < cube.side && b < cube.side && c < cube.side) {
              const std::uint64_t bit = static_cast<std::uint64_t>((a * cube.side + b) * cube.side + c);
              std::uint64_t& word = seen_[bit >> 6];
              const std::uint64_t mask = std::uint64_t(1) << (bit & 63u);
              if (word & mask) continue;
              word |= mask;
            }
          }
          free_codes_.push_back(morton(k));
        }
      }
    }
    sort_unique(free_codes_);

    // Hits: Morton code and label, ascending; the end voxels' codes.
    hit_votes_.resize(keyed.size());
    for (std::size_t i = 0; i < keyed.size(); ++i) {
      hit_votes_[i] = Vote{morton(unpack(keyed[i].first)), keyed[i].second, 1};
    }
    std::sort(hit_votes_.begin(), hit_votes_.end(), vote_less);
    hit_codes_.resize(hit_count);
    for (std::size_t i = 0; i < hit_count; ++i) hit_codes_[i] = morton(unpack(ends[i]));
    std::sort(hit_codes_.begin(), hit_codes_.end());

    // Log-odds updates: each cell once per scan, hits win over misses.
    misses_.clear();
    std::set_difference(free_codes_.begin(), free_codes_.end(), hit_codes_.begin(), hit_codes_.end(),
                        std::back_inserter(misses_));
    update_leaves(misses_, tree_->getProbMissLog(), [](octomap::ColorOcTreeNode*, std::size_t) {});
    inner_stale_ = true;

    // Votes: merge this scan's (code, label, points) into votes_; the colour of each hit voxel is the
    // preset colour of its label with the most votes (ties: the smaller label).
    std::vector<std::uint16_t> best = merge_votes();
    update_leaves(hit_codes_, tree_->getProbHitLog(), [&](octomap::ColorOcTreeNode* node, std::size_t i) {
      const mapping::Rgb8 c = mapping::class_colour(best[i]);
      node->setColor(c.r, c.g, c.b);
    });
  }

  /// The occupied voxels with their colours and classes.
  mapping::OccupiedVoxels occupied_voxels() const { return octomap_adapter::occupied_voxels(*tree_); }

  /// OctoMap's memoryUsage() of the tree plus the class votes, bytes.
  std::size_t memory_bytes() const { return tree_->memoryUsage() + votes_.capacity() * sizeof(Vote); }
  std::size_t tree_memory_bytes() const { return tree_->memoryUsage(); }

  /// The ColorOcTree (.ot, opened by octovis). Throws std::invalid_argument when the file exists and
  /// !overwrite, std::runtime_error naming it when it cannot be written.
  void write_ot(const std::filesystem::path& path, bool overwrite = false) {
    refuse_existing(path, overwrite);
    update_inner();
    io::StderrCapture octomap_messages;  // OctoMap's progress lines ("... done.") are not the tool's output
    if (!tree_->write(path.string())) {
      throw std::runtime_error("SemanticOctree: cannot write " + path.string() + with_messages(octomap_messages));
    }
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
    io::StderrCapture octomap_messages;  // as write_ot
    if (!plain.writeBinary(path.string())) {
      throw std::runtime_error("SemanticOctree: cannot write " + path.string() + with_messages(octomap_messages));
    }
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
  /// What OctoMap wrote to standard error during a failed write, as a suffix for the message.
  static std::string with_messages(io::StderrCapture& capture) {
    std::cerr.flush();
    const std::string text = capture.finish();
    return text.empty() ? std::string() : " (OctoMap: " + text + ")";
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

  /// Points of one class label seen in one end voxel (Morton code) over all scans.
  struct Vote {
    std::uint64_t code;
    std::uint16_t label;
    std::uint32_t points;
  };
  static bool vote_less(const Vote& a, const Vote& b) { return a.code != b.code ? a.code < b.code : a.label < b.label; }

  /// The key's Morton code: bit l of key[0], key[1], key[2] at bits 3l, 3l + 1, 3l + 2, so that
  /// (code >> 3l) & 7 is the child index OctoMap takes at level l and ascending codes walk the tree
  /// depth first.
  static std::uint64_t morton(const octomap::OcTreeKey& k) {
    const auto spread = [](std::uint64_t x) {  // 16 bits to every third bit
      x = (x | (x << 16)) & 0x0000FF0000FFull;
      x = (x | (x << 8)) & 0x00F00F00F00Full;
      x = (x | (x << 4)) & 0x0C30C30C30C3ull;
      x = (x | (x << 2)) & 0x249249249249ull;
      return x;
    };
    return spread(k[0]) | (spread(k[1]) << 1) | (spread(k[2]) << 2);
  }
  static octomap::OcTreeKey key_of_morton(std::uint64_t m) {
    const auto compact = [](std::uint64_t x) {
      x &= 0x249249249249ull;
      x = (x | (x >> 2)) & 0x0C30C30C30C3ull;
      x = (x | (x >> 4)) & 0x00F00F00F00Full;
      x = (x | (x >> 8)) & 0x0000FF0000FFull;
      x = (x | (x >> 16)) & 0xFFFFull;
      return static_cast<octomap::key_type>(x);
    };
    return octomap::OcTreeKey(compact(m), compact(m >> 1), compact(m >> 2));
  }

  /// The cube of keys within max range of an origin, as a bit set of side `side` starting at key
  /// `first`; side 0 when the cube would exceed kMaxSeenBits (then the sort alone deduplicates).
  struct SeenCube {
    std::int64_t first[3] = {0, 0, 0};
    std::int64_t side = 0;
  };
  static constexpr std::int64_t kMaxSeenBits = std::int64_t(1) << 27;  ///< 16 MiB of bits at most
  SeenCube seen_cube(const octomap::point3d& origin) {
    SeenCube cube;
    octomap::OcTreeKey centre;
    if (!tree_->coordToKeyChecked(origin, centre)) return cube;
    const std::int64_t reach = static_cast<std::int64_t>(std::ceil(settings_.max_range_m / settings_.resolution_m)) + 2;
    const std::int64_t side = 2 * reach + 1;
    if (side > 1024 || side * side * side > kMaxSeenBits) return cube;
    for (int k = 0; k < 3; ++k) cube.first[k] = static_cast<std::int64_t>(centre[k]) - reach;
    cube.side = side;
    seen_.assign(static_cast<std::size_t>((side * side * side + 63) / 64), 0);
    return cube;
  }

  /// The index of the highest set bit of x != 0.
  static int highest_bit(std::uint64_t x) {
#if defined(__GNUC__) || defined(__clang__)
    return 63 - __builtin_clzll(x);
#else
    int bit = 63;
    while (!((x >> bit) & 1u)) --bit;
    return bit;
#endif
  }

  /// Sorts 48-bit codes and removes repeats: a least-significant-digit radix sort (3 passes of 16 bits).
  void sort_unique(std::vector<std::uint64_t>& codes) {
    radix_buffer_.resize(codes.size());
    std::vector<std::size_t> count(1u << 16);
    for (int shift = 0; shift < 48; shift += 16) {
      std::fill(count.begin(), count.end(), 0);
      for (const std::uint64_t c : codes) ++count[(c >> shift) & 0xffffu];
      std::size_t sum = 0;
      for (std::size_t& n : count) sum += std::exchange(n, sum);
      for (const std::uint64_t c : codes) radix_buffer_[count[(c >> shift) & 0xffffu]++] = c;
      codes.swap(radix_buffer_);
    }
    codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  }

  /// Adds `log_odds` to every leaf whose Morton code is in `codes` (ascending, unique), exactly as
  /// updateNode(key, log_odds, lazy_eval = true) would key by key (OctoMap 1.9: create missing
  /// children, expand a pruned leaf, add and clamp), but walking the tree once in depth-first order:
  /// consecutive codes share the path above their first different child index. Calls
  /// on_leaf(leaf, index in codes) after each update.
  template <typename OnLeaf>
  void update_leaves(const std::vector<std::uint64_t>& codes, float log_odds, OnLeaf&& on_leaf) {
    if (codes.empty()) return;
    std::size_t first = 0;
    if (tree_->getRoot() == nullptr) {  // only updateNode can create the root
      on_leaf(tree_->updateNode(key_of_morton(codes[0]), log_odds, /*lazy_eval=*/true), 0);
      first = 1;
    }
    const int depth = static_cast<int>(tree_->getTreeDepth());
    std::vector<octomap::ColorOcTreeNode*> path(static_cast<std::size_t>(depth) + 1, nullptr);
    std::vector<char> created(static_cast<std::size_t>(depth) + 1, 0);
    path[0] = tree_->getRoot();
    std::uint64_t previous = 0;
    for (std::size_t i = first; i < codes.size(); ++i) {
      const std::uint64_t code = codes[i];
      int d = 0;  // the first depth whose child index differs from the previous code's
      if (i > first) {
        d = depth - 1 - highest_bit(code ^ previous) / 3;
      }
      for (; d < depth; ++d) {
        octomap::ColorOcTreeNode* node = path[static_cast<std::size_t>(d)];
        const unsigned pos = static_cast<unsigned>((code >> (3 * (depth - 1 - d))) & 7u);
        bool made = false;
        if (!tree_->nodeChildExists(node, pos)) {
          if (!tree_->nodeHasChildren(node) && !created[static_cast<std::size_t>(d)]) {
            tree_->expandNode(node);
          } else {
            tree_->createNodeChild(node, pos);
            made = true;
          }
        }
        path[static_cast<std::size_t>(d) + 1] = tree_->getNodeChild(node, pos);
        created[static_cast<std::size_t>(d) + 1] = made;
      }
      octomap::ColorOcTreeNode* leaf = path[static_cast<std::size_t>(depth)];
      tree_->updateNodeLogOdds(leaf, log_odds);
      on_leaf(leaf, i);
      previous = code;
    }
  }

  /// Merges hit_votes_ (one vote per point, sorted by vote_less) into votes_ and returns, for each
  /// code of hit_codes_, the label with the most points over all scans so far (ties: the smaller).
  std::vector<std::uint16_t> merge_votes() {
    merged_.clear();
    merged_.reserve(votes_.size() + hit_votes_.size());
    std::size_t a = 0, b = 0;
    while (a < votes_.size() || b < hit_votes_.size()) {
      if (b == hit_votes_.size() || (a < votes_.size() && vote_less(votes_[a], hit_votes_[b]))) {
        merged_.push_back(votes_[a++]);
      } else if (a == votes_.size() || vote_less(hit_votes_[b], votes_[a])) {
        merged_.push_back(hit_votes_[b++]);
      } else {
        merged_.push_back(votes_[a++]);
      }
      while (b < hit_votes_.size() && hit_votes_[b].code == merged_.back().code &&
             hit_votes_[b].label == merged_.back().label) {
        merged_.back().points += hit_votes_[b++].points;
      }
    }
    votes_.swap(merged_);
    std::vector<std::uint16_t> best(hit_codes_.size(), 0);
    std::size_t v = 0;
    for (std::size_t i = 0; i < hit_codes_.size(); ++i) {
      while (votes_[v].code < hit_codes_[i]) ++v;
      std::uint32_t most = 0;
      for (; v < votes_.size() && votes_[v].code == hit_codes_[i]; ++v) {
        if (votes_[v].points > most) {  // labels ascend: a later label wins only with strictly more
          most = votes_[v].points;
          best[i] = votes_[v].label;
        }
      }
    }
    return best;
  }

  SemanticOctreeSettings settings_;
  std::unique_ptr<octomap::ColorOcTree> tree_;
  /// Per end voxel and label (sorted by vote_less): points over all scans.
  std::vector<Vote> votes_;
  bool inner_stale_ = false;
  // Buffers reused from scan to scan (their contents do not outlive insert_scan).
  octomap::KeyRay ray_;
  std::vector<std::uint64_t> free_codes_, hit_codes_, misses_, radix_buffer_;
  std::vector<std::uint64_t> seen_;  ///< SeenCube bits of the current scan
  std::vector<Vote> hit_votes_, merged_;
};

}  // namespace octomap_adapter
}  // namespace cge
