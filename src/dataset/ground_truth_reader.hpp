#pragma once
// Private: the groundtruth.txt reader of TumSequence. Kept out of the public headers because the
// core TUM trajectory reader (include/cge/metrics/) will replace it.

#include <filesystem>
#include <vector>

#include "cge/dataset/tum_sequence.hpp"

namespace cge {
namespace dataset {
namespace detail {

/// Parses `timestamp tx ty tz qx qy qz qw` lines ('#' comments and blank lines ignored) into poses,
/// quaternions normalised. Throws std::invalid_argument "<file>:<line>: ..." for a line without 8
/// fields, a number that does not parse, a quaternion whose norm is off 1 by more than
/// quaternion_norm_tolerance, or a timestamp smaller than the previous one (equal
/// ones are kept, in file order: TUM's fr2_desk has some); naming the file
/// when it cannot be read.
std::vector<GroundTruthPose> read_ground_truth(const std::filesystem::path& file, double quaternion_norm_tolerance);

}  // namespace detail
}  // namespace dataset
}  // namespace cge
