#pragma once
// What a keyframe policy sees of a frame: built by the caller once per frame, no images, no
// keypoints. make_frame_summary() builds one from keypoints and semantic instances.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "cge/core/semantic_instance.hpp"
#include "cge/frontend/patch_grid.hpp"
#include "cge/frontend/patch_statistics.hpp"

namespace cge {

/// Frame id meaning "no frame" in decisions and queries. Real frame ids are >= 0.
constexpr std::int64_t kNoFrame = -1;

template <typename Scalar>
struct FrameSummary {
  using Point = Eigen::Matrix<Scalar, 2, 1>;

  /// Names the frame in decisions; >= 0 and strictly increasing along a sequence (gaps allowed:
  /// policies count frames by calls, not by id differences).
  std::int64_t frame_id = 0;
  /// The image and its n x m patches; must match the patch policy's settings.
  PatchGrid<Scalar> grid;
  /// Features per patch, row-major (patch = row * cols + col), grid.patch_count() entries. Count the
  /// features the tracker keeps (normally those left after dynamic-feature elimination). Only the
  /// patch policy reads it; the ORB-SLAM2 baseline accepts it empty.
  std::vector<int> patch_counts;
  /// Centres of the semantic instances the keyframe rule counts, pixels: make_frame_summary() keeps
  /// all classes; PatchKeyframeSelector::summarise() only dynamic ones unless its settings say
  /// otherwise. Their number is Num for the semantic-change rule.
  std::vector<Point> instance_centres_px;
  /// Map points tracked in this frame (inliers after pose optimisation), >= 0.
  int tracked_points = 0;
  /// Keypoints with a close depth (ORB-SLAM2: closer than ThDepth baselines) that track a map point,
  /// and those that do not; -1 when the host does not count them (the ORB-SLAM2 baseline's
  /// close-point rule and the patch policy's coverage guard then stay off).
  int tracked_close_points = -1;
  int untracked_close_points = -1;

  int instance_count() const { return static_cast<int>(instance_centres_px.size()); }

  /// Checks what every policy needs: id and tracked points non-negative, a valid grid, instance
  /// centres finite and inside the image. Throws std::invalid_argument naming the frame and field.
  void validate() const {
    if (frame_id < 0) {
      std::ostringstream msg;
      msg << "FrameSummary: frame_id must be >= 0, got " << frame_id;
      throw std::invalid_argument(msg.str());
    }
    if (tracked_points < 0) {
      std::ostringstream msg;
      msg << "FrameSummary: frame " << frame_id << " has a negative tracked_points " << tracked_points;
      throw std::invalid_argument(msg.str());
    }
    grid.validate();
    for (std::size_t i = 0; i < instance_centres_px.size(); ++i) {
      const Point& c = instance_centres_px[i];
      if (!std::isfinite(c.x()) || !std::isfinite(c.y()) || !grid.image.contains(c)) {
        std::ostringstream msg;
        msg << "FrameSummary: frame " << frame_id << ", instance #" << i << " has centre (" << c.x() << ", " << c.y()
            << ") that is not finite or lies outside the image region";
        throw std::invalid_argument(msg.str());
      }
    }
  }

  /// Additionally checks the patch counts: grid.patch_count() non-negative entries.
  void validate_patch_counts() const {
    if (patch_counts.size() != static_cast<std::size_t>(grid.patch_count())) {
      std::ostringstream msg;
      msg << "FrameSummary: frame " << frame_id << " has " << patch_counts.size() << " patch counts for a grid of "
          << grid.cols << " x " << grid.rows;
      throw std::invalid_argument(msg.str());
    }
    for (std::size_t i = 0; i < patch_counts.size(); ++i) {
      if (patch_counts[i] < 0) {
        std::ostringstream msg;
        msg << "FrameSummary: frame " << frame_id << ", patch " << i << " has a negative count " << patch_counts[i];
        throw std::invalid_argument(msg.str());
      }
    }
  }
};

/// The summary of one frame from its keypoints (any range of points adapted by cge::traits::Point2)
/// and semantic instances (all classes). Throws std::invalid_argument for keypoints or instance
/// centres that are not finite or lie outside the image, a bad grid, or bad id / tracked points.
template <typename Scalar, typename Keypoints>
FrameSummary<Scalar> make_frame_summary(std::int64_t frame_id, const PatchGrid<Scalar>& grid,
                                        const Keypoints& keypoints,
                                        const std::vector<SemanticInstance<Scalar>>& instances, int tracked_points) {
  FrameSummary<Scalar> s;
  s.frame_id = frame_id;
  s.grid = grid;
  s.tracked_points = tracked_points;
  s.instance_centres_px.reserve(instances.size());
  for (const auto& inst : instances) s.instance_centres_px.push_back(inst.centre_px);
  s.validate();
  s.patch_counts = count_patch_features(grid, keypoints);
  return s;
}

}  // namespace cge
