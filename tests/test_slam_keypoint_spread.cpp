// spread_over_cells (cge/slam/keypoint_spread.hpp): a hand-worked case, and on random candidate
// sets the rule's definition checked property by property: each level's share, best-first inside a
// cell, round-robin across cells (no cell two ahead of one that still has candidates), candidate
// order kept.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstddef>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "cge/slam/keypoint_spread.hpp"

namespace {

using cge::slam::spread_over_cells;

cv::KeyPoint candidate(float x, float y, float response, int octave) {
  cv::KeyPoint k(x, y, 31.f, -1.f, response, octave);
  return k;
}

bool same_keypoint(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  return a.pt == b.pt && a.response == b.response && a.octave == b.octave;
}

}  // namespace

TEST_CASE("spread_over_cells: a hand-worked case on two cells of one level", "[slam][features]") {
  // Cells of 32 px. Cell (0,0) holds responses 9, 8, 7; cell (0,1) holds 5 and 4. Oversampling 2
  // keeps round(5 / 2) = 3 (halves up): the best of each cell (9, then 5), then the second best of
  // the cell whose best is strongest (8).
  const std::vector<cv::KeyPoint> c = {candidate(1, 1, 7, 0), candidate(40, 2, 4, 0), candidate(2, 2, 9, 0),
                                       candidate(3, 3, 8, 0), candidate(41, 5, 5, 0)};
  const std::vector<cv::KeyPoint> kept = spread_over_cells(c, 2, 32, 1.2);
  REQUIRE(kept.size() == 3);
  // Candidate order is kept: 9 (index 2), 8 (index 3), 5 (index 4).
  CHECK(same_keypoint(kept[0], c[2]));
  CHECK(same_keypoint(kept[1], c[3]));
  CHECK(same_keypoint(kept[2], c[4]));
  // Without spreading the three strongest would all be in cell (0,0).
}

TEST_CASE("spread_over_cells: oversampling 1 returns the candidates unchanged", "[slam][features]") {
  const std::vector<cv::KeyPoint> c = {candidate(1, 1, 7, 0), candidate(40, 2, 4, 1), candidate(2, 2, 9, 2)};
  const std::vector<cv::KeyPoint> kept = spread_over_cells(c, 1, 32, 1.2);
  REQUIRE(kept.size() == c.size());
  for (std::size_t i = 0; i < c.size(); ++i) CHECK(same_keypoint(kept[i], c[i]));
  CHECK(spread_over_cells({}, 2, 32, 1.2).empty());
}

TEST_CASE("spread_over_cells: level shares, best first per cell, round robin, order (random sets)",
          "[slam][features][property]") {
  std::mt19937 rng(20261204);
  for (int trial = 0; trial < 200; ++trial) {
    const int levels = 1 + static_cast<int>(rng() % 4);
    const int count = 1 + static_cast<int>(rng() % 400);
    const int cell_px = 8 + static_cast<int>(rng() % 40);
    const double scale = 1.2;
    std::vector<cv::KeyPoint> c;
    for (int i = 0; i < count; ++i) {
      // Few distinct responses, so ties (broken by candidate order) are common.
      c.push_back(candidate(static_cast<float>(rng() % 640), static_cast<float>(rng() % 480),
                            static_cast<float>(rng() % 20), static_cast<int>(rng() % static_cast<unsigned>(levels))));
    }
    const int oversampling = 1 + static_cast<int>(rng() % 4);
    const std::vector<cv::KeyPoint> kept = spread_over_cells(c, oversampling, cell_px, scale);

    // Which candidates were kept: the output is an ordered subsequence of the input.
    std::vector<char> is_kept(c.size(), 0);
    std::size_t next = 0;
    for (const cv::KeyPoint& k : kept) {
      while (next < c.size() && !same_keypoint(c[next], k)) ++next;
      REQUIRE(next < c.size());
      is_kept[next++] = 1;
    }

    std::map<int, std::vector<std::size_t>> by_level;
    for (std::size_t i = 0; i < c.size(); ++i) by_level[c[i].octave].push_back(i);
    for (const auto& [level, members] : by_level) {
      // The level's share: round(members / oversampling), halves up.
      const double exact = static_cast<double>(members.size()) / oversampling;
      const std::size_t share = static_cast<std::size_t>(std::floor(exact + 0.5));
      std::size_t kept_here = 0;
      for (const std::size_t i : members) kept_here += static_cast<std::size_t>(is_kept[i]);
      CHECK(kept_here == share);

      const double cell = cell_px * std::pow(scale, level);
      std::map<std::pair<int, int>, std::vector<std::size_t>> cells;
      for (const std::size_t i : members) {
        cells[{static_cast<int>(c[i].pt.y / cell), static_cast<int>(c[i].pt.x / cell)}].push_back(i);
      }
      std::map<std::pair<int, int>, std::size_t> kept_in_cell;
      for (const auto& [key, in_cell] : cells) {
        std::size_t n = 0;
        for (const std::size_t i : in_cell) n += static_cast<std::size_t>(is_kept[i]);
        kept_in_cell[key] = n;
        // Best first: no dropped candidate is stronger than a kept one of its cell (ties: earlier first).
        for (const std::size_t a : in_cell) {
          for (const std::size_t b : in_cell) {
            const bool a_stronger = c[a].response > c[b].response || (c[a].response == c[b].response && a < b);
            if (a_stronger && is_kept[b]) CHECK(is_kept[a]);
          }
        }
      }
      // Round robin: a cell with a candidate left is never two or more behind another cell.
      for (const auto& [key, in_cell] : cells) {
        if (kept_in_cell[key] == in_cell.size()) continue;
        for (const auto& [other, n] : kept_in_cell) CHECK(n <= kept_in_cell[key] + 1);
      }
    }
  }
}
