#pragma once
// A run's loop decisions against the ground-truth loops: the stamps the loop closer queried, the
// ground-truth loops file of a rendered run, and the report of the accepted loops and the figures
// (docs/EVALUATION.md).
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/metrics/loop_precision_recall.hpp"
#include "cge/run/frame_source.hpp"
#include "cge/slam/system.hpp"

namespace cge {
namespace run {

/// A timestamp as the loop files spell it ("%.6f"): the key that matches stamps across files.
std::string stamp_text(double timestamp_s);

/// The stamps of the keyframes the loop closer queried.
std::set<std::string> queried_stamps(const std::vector<slam::LoopRecord>& loops);

/// loops.txt as cge_sim writes it (stamps as the rendered frames' stems).
void write_ground_truth_loops(std::ostream& out, const std::vector<metrics::GroundTruthLoop>& loops);

/// One line per accepted loop, marked correct or wrong against `ground_truth` and, where `poses`
/// have both stamps, with how far apart the two cameras really were (centres, metres; optical
/// axes, degrees); then the figures of `evaluation` as `name value` lines (precision and recalls
/// nan when their denominator is 0).
std::string loop_evaluation_report(const std::vector<slam::LoopRecord>& loops,
                                   const std::vector<metrics::GroundTruthLoop>& ground_truth,
                                   const GroundTruthPoses& poses, const metrics::LoopEvaluation& evaluation);

}  // namespace run
}  // namespace cge
