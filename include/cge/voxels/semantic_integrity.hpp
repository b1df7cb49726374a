#pragma once
// Semantic integrity and fluctuation of a semantic map (docs/METHOD.md section 8, after Zhang et al.).
//
// An entity is a class label with an axis-aligned bounding box of voxels (its "bounding cube").
// For each entity: T_N = occupied voxels inside the box (any colour), T_O = those of the entity's
// class, S_int = T_O / T_N. Entities whose box holds no occupied voxel are skipped.
//   Score_INT = sum T_N S_int / sum T_N,  Score_flu = sqrt(sum T_N (S_int - Score_INT)^2 / sum T_N).
// Two entity sources: per keyframe and class (SemanticMapBuilder, from the pixels of each class a
// keyframe sees), and, when only the map is at hand (cge_eval map), the 26-connected components of
// voxels of one class in the map itself.
//
// Ghost voxels: occupied voxels in a given set of "ghost" voxel indices (where a moving person was
// and no static surface is; cge/mapping/ghost_voxels.hpp makes the set from a synthetic sequence).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cge/voxels/map_voxel.hpp"

namespace cge {
namespace mapping {

struct IntegrityEntity {
  std::uint16_t class_label = 0;              ///< COCO id + 1 (> 0)
  VoxelIndex min_index = VoxelIndex::Zero();  ///< box corner, inclusive
  VoxelIndex max_index = VoxelIndex::Zero();  ///< box corner, inclusive
};

struct IntegrityScores {
  double integrity = 0;    ///< Score_INT in [0, 1] (0 when no entity was scored)
  double fluctuation = 0;  ///< Score_flu >= 0
  int entities = 0;        ///< entities with T_N > 0
};

/// Scores of `entities` against the map's occupied voxels (sorted by voxel_less, as OccupiedVoxels).
/// Cost: O(entities x log voxels + voxels in the boxes) by scanning the x-range of each box.
inline IntegrityScores integrity_scores(const OccupiedVoxels& map, const std::vector<IntegrityEntity>& entities) {
  const std::vector<MapVoxel>& v = map.voxels;
  std::vector<double> s_int, t_n;
  for (const IntegrityEntity& e : entities) {
    const auto first =
        std::lower_bound(v.begin(), v.end(), e.min_index.x(), [](const MapVoxel& a, int x) { return a.index.x() < x; });
    std::size_t total = 0, own = 0;
    for (auto it = first; it != v.end() && it->index.x() <= e.max_index.x(); ++it) {
      const VoxelIndex& i = it->index;
      if (i.y() < e.min_index.y() || i.y() > e.max_index.y() || i.z() < e.min_index.z() || i.z() > e.max_index.z())
        continue;
      ++total;
      own += it->class_label == e.class_label;
    }
    if (total == 0) continue;
    t_n.push_back(static_cast<double>(total));
    s_int.push_back(static_cast<double>(own) / static_cast<double>(total));
  }
  IntegrityScores out;
  out.entities = static_cast<int>(t_n.size());
  double weight = 0, weighted = 0;
  for (std::size_t i = 0; i < t_n.size(); ++i) {
    weight += t_n[i];
    weighted += t_n[i] * s_int[i];
  }
  if (weight == 0) return out;
  out.integrity = weighted / weight;
  double spread = 0;
  for (std::size_t i = 0; i < t_n.size(); ++i)
    spread += t_n[i] * (s_int[i] - out.integrity) * (s_int[i] - out.integrity);
  out.fluctuation = std::sqrt(spread / weight);
  return out;
}

/// The 26-connected components of voxels of one class (class_label > 0) as entities, in the order
/// of their first voxel (voxel_less). Components smaller than min_voxels are left out (noise).
inline std::vector<IntegrityEntity> component_entities(const OccupiedVoxels& map, std::size_t min_voxels = 1) {
  const std::vector<MapVoxel>& v = map.voxels;
  const auto find = [&v](const VoxelIndex& i) -> std::ptrdiff_t {
    const auto it = std::lower_bound(v.begin(), v.end(), i,
                                     [](const MapVoxel& a, const VoxelIndex& b) { return voxel_less(a.index, b); });
    return (it != v.end() && it->index == i) ? it - v.begin() : -1;
  };
  std::vector<char> seen(v.size(), 0);
  std::vector<IntegrityEntity> out;
  std::vector<std::size_t> stack;
  for (std::size_t s = 0; s < v.size(); ++s) {
    if (seen[s] || v[s].class_label == 0) continue;
    IntegrityEntity e;
    e.class_label = v[s].class_label;
    e.min_index = e.max_index = v[s].index;
    std::size_t count = 0;
    stack.assign(1, s);
    seen[s] = 1;
    while (!stack.empty()) {
      const std::size_t c = stack.back();
      stack.pop_back();
      ++count;
      e.min_index = e.min_index.cwiseMin(v[c].index);
      e.max_index = e.max_index.cwiseMax(v[c].index);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::ptrdiff_t n = find(v[c].index + VoxelIndex(dx, dy, dz));
            if (n < 0 || seen[static_cast<std::size_t>(n)] ||
                v[static_cast<std::size_t>(n)].class_label != e.class_label)
              continue;
            seen[static_cast<std::size_t>(n)] = 1;
            stack.push_back(static_cast<std::size_t>(n));
          }
    }
    if (count >= min_voxels) out.push_back(e);
  }
  return out;
}

/// The number of occupied voxels of `map` whose index is in `ghost_indices` (sorted by voxel_less, unique).
inline std::size_t ghost_voxel_count(const OccupiedVoxels& map, const std::vector<VoxelIndex>& ghost_indices) {
  std::size_t ghosts = 0;
  for (const MapVoxel& m : map.voxels) {
    ghosts += std::binary_search(ghost_indices.begin(), ghost_indices.end(), m.index,
                                 [](const VoxelIndex& a, const VoxelIndex& b) { return voxel_less(a, b); });
  }
  return ghosts;
}

/// Fraction of the map's occupied voxels whose index is in `ghost_indices` (sorted by voxel_less,
/// unique); 0 for an empty map.
inline double ghost_fraction(const OccupiedVoxels& map, const std::vector<VoxelIndex>& ghost_indices) {
  if (map.voxels.empty()) return 0;
  return static_cast<double>(ghost_voxel_count(map, ghost_indices)) / static_cast<double>(map.voxels.size());
}

}  // namespace mapping
}  // namespace cge
