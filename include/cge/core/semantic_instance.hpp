#pragma once
// A segmented object instance as the graph and similarity components see it.

#include <Eigen/Core>

namespace cge {

/// One instance found by a segmenter in a frame. Only its centre, class and whether its class is
/// dynamic matter to graph construction and the semantic pre-judgment; masks are handled elsewhere.
template <typename Scalar>
struct SemanticInstance {
  Eigen::Matrix<Scalar, 2, 1> centre_px = Eigen::Matrix<Scalar, 2, 1>::Zero();  ///< box centre, pixels
  int class_id = 0;      ///< e.g. a COCO class index; any non-negative integer
  bool dynamic = false;  ///< true for classes treated as moving (COCO "person" by default)
};

}  // namespace cge
