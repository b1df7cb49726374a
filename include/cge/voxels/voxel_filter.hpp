#pragma once
// Deterministic voxel filter of a semantic cloud: one point per occupied voxel.
//
// Output point of a voxel: the centroid of its points (summed in double in input order), the class
// label with the most points (ties: the smaller label), and the mean colour (rounded) of the points
// that carry that label. Voxels come out in voxel_less order. No hashing: the result depends on the
// input sequence only, bit for bit.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <utility>
#include <vector>

#include "cge/voxels/map_voxel.hpp"
#include "cge/voxels/semantic_point.hpp"

namespace cge {
namespace mapping {

/// The filtered cloud (see above). Throws std::invalid_argument for voxel_m not finite and > 0 or
/// a non-finite point.
inline std::vector<SemanticPoint> voxel_filter(const std::vector<SemanticPoint>& points, double voxel_m) {
  // Sorted by (voxel, input index): every voxel's points stay in input order. Voxel indices are
  // ordered as voxel_less through one 64-bit key when they fit in 21 bits each (the usual case).
  std::vector<std::pair<VoxelIndex, std::size_t>> keyed;
  keyed.reserve(points.size());
  bool packable = true;
  for (std::size_t i = 0; i < points.size(); ++i) {
    keyed.emplace_back(voxel_of(points[i].position_m, voxel_m), i);
    packable = packable && (keyed.back().first.array().abs() < (1 << 20)).all();
  }
  if (packable && !keyed.empty()) {
    // Key relative to the cloud's voxel box, (x, y, z) lexicographic, sorted by a stable
    // least-significant-digit radix sort: equal keys keep input order.
    VoxelIndex lo = keyed[0].first, hi = keyed[0].first;
    for (const auto& k : keyed) {
      lo = lo.cwiseMin(k.first);
      hi = hi.cwiseMax(k.first);
    }
    const VoxelIndex extent = hi - lo + VoxelIndex::Ones();  // each < 2^21: the product fits 63 bits
    const auto pack = [&](const VoxelIndex& v) {
      const VoxelIndex d = v - lo;
      return (static_cast<std::uint64_t>(d.x()) * static_cast<std::uint64_t>(extent.y()) +
              static_cast<std::uint64_t>(d.y())) *
                 static_cast<std::uint64_t>(extent.z()) +
             static_cast<std::uint64_t>(d.z());
    };
    const std::uint64_t largest = pack(hi);
    std::vector<std::pair<std::uint64_t, std::size_t>> packed(keyed.size()), buffer(keyed.size());
    for (std::size_t i = 0; i < keyed.size(); ++i) packed[i] = {pack(keyed[i].first), i};
    constexpr int kDigitBits = 11;
    std::vector<std::size_t> count(std::size_t(1) << kDigitBits);
    for (int shift = 0; shift < 64 && (largest >> shift) != 0; shift += kDigitBits) {
      std::fill(count.begin(), count.end(), 0);
      const std::uint64_t digit_mask = (std::uint64_t(1) << kDigitBits) - 1;
      for (const auto& e : packed) ++count[(e.first >> shift) & digit_mask];
      std::size_t sum = 0;
      for (std::size_t& n : count) sum += std::exchange(n, sum);
      for (const auto& e : packed) buffer[count[(e.first >> shift) & digit_mask]++] = e;
      packed.swap(buffer);
    }
    std::vector<std::pair<VoxelIndex, std::size_t>> sorted(keyed.size());
    for (std::size_t i = 0; i < packed.size(); ++i) sorted[i] = keyed[packed[i].second];
    keyed.swap(sorted);
  } else {
    std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) {
      if (a.first != b.first) return voxel_less(a.first, b.first);
      return a.second < b.second;
    });
  }

  std::vector<SemanticPoint> out;
  std::vector<std::pair<std::uint16_t, std::size_t>> labels;  // (label, index) of one voxel, sorted by label
  for (std::size_t begin = 0; begin < keyed.size();) {
    std::size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    labels.clear();
    while (end < keyed.size() && keyed[end].first == keyed[begin].first) {
      const SemanticPoint& p = points[keyed[end].second];
      sum += p.position_m.cast<double>();
      labels.emplace_back(p.class_label, keyed[end].second);
      ++end;
    }
    std::stable_sort(labels.begin(), labels.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    // Majority label (the first, i.e. smallest, among equals) and the run of its points.
    std::size_t best_begin = 0, best_count = 0;
    for (std::size_t i = 0; i < labels.size();) {
      std::size_t j = i;
      while (j < labels.size() && labels[j].first == labels[i].first) ++j;
      if (j - i > best_count) {
        best_count = j - i;
        best_begin = i;
      }
      i = j;
    }
    std::uint32_t r = 0, g = 0, b = 0;
    for (std::size_t i = best_begin; i < best_begin + best_count; ++i) {
      const Rgb8& c = points[labels[i].second].colour;
      r += c.r;
      g += c.g;
      b += c.b;
    }
    const auto mean = [best_count](std::uint32_t s) {
      return static_cast<std::uint8_t>((s + static_cast<std::uint32_t>(best_count / 2)) /
                                       static_cast<std::uint32_t>(best_count));
    };
    SemanticPoint q;
    q.position_m = (sum / static_cast<double>(end - begin)).cast<float>();
    q.class_label = labels[best_begin].first;
    q.colour = Rgb8{mean(r), mean(g), mean(b)};
    out.push_back(q);
    begin = end;
  }
  return out;
}

/// The voxels of side resolution_m (voxel_of grid) that hold points of the cloud, as a map: the
/// label with the most points (ties: the smaller), coloured class_colour(label). Lets the ghost
/// fraction and the pictures treat the dense cloud like the octree (a cloud has no free space).
inline OccupiedVoxels occupied_voxels_of_cloud(const std::vector<SemanticPoint>& points, double resolution_m) {
  std::vector<std::pair<VoxelIndex, std::uint16_t>> keyed;
  keyed.reserve(points.size());
  for (const SemanticPoint& p : points) keyed.emplace_back(voxel_of(p.position_m, resolution_m), p.class_label);
  std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return voxel_less(a.first, b.first);
    return a.second < b.second;
  });
  OccupiedVoxels out;
  out.resolution_m = resolution_m;
  for (std::size_t i = 0; i < keyed.size();) {
    MapVoxel v;
    v.index = keyed[i].first;
    std::size_t best = 0;
    while (i < keyed.size() && keyed[i].first == v.index) {
      std::size_t j = i;
      while (j < keyed.size() && keyed[j].first == v.index && keyed[j].second == keyed[i].second) ++j;
      if (j - i > best) {  // labels ascend: a later label wins only with strictly more points
        best = j - i;
        v.class_label = keyed[i].second;
      }
      i = j;
    }
    v.colour = class_colour(v.class_label);
    v.class_label = class_label_of_colour(v.colour);  // as read back from an octree: presets only
    out.voxels.push_back(v);
  }
  return out;
}

}  // namespace mapping
}  // namespace cge
