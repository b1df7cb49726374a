#pragma once
/// Spreading ORB keypoints over the image (OrbSettings::spread_oversampling): cv::ORB keeps the
/// corners with the best Harris scores, so a few textured regions take most of a frame's features;
/// ORB-SLAM2 spreads each pyramid level's corners over the image instead. This keeps a given number
/// of an oversampled candidate set, level by level, taking the best of every cell in turn.

#include <cstddef>
#include <vector>

#include <opencv2/core/types.hpp>

namespace cge {
namespace slam {

/// Keeps about one in `oversampling` of `candidates`: each pyramid level (KeyPoint::octave) keeps
/// round(level's candidates / oversampling), halves up, and takes them cell by cell: the best
/// response of every cell, then every cell's second best, ... (cells visited by their best
/// response, ties broken by candidate order). Cells are `cell_px` square at level 0 and scale with
/// scale_factor^octave. Kept keypoints stay in candidate order. Deterministic; oversampling >= 1,
/// cell_px >= 1 and scale_factor > 0 are the caller's to check (OrbSettings::validate does).
std::vector<cv::KeyPoint> spread_over_cells(const std::vector<cv::KeyPoint>& candidates, int oversampling,
                                            int cell_px, double scale_factor);

}  // namespace slam
}  // namespace cge
