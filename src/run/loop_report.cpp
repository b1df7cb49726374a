#include "cge/run/loop_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

namespace cge {
namespace run {

std::string stamp_text(double timestamp_s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6f", timestamp_s);
  return text;
}

std::set<std::string> queried_stamps(const std::vector<slam::LoopRecord>& loops) {
  std::set<std::string> queried;
  for (const slam::LoopRecord& l : loops) queried.insert(stamp_text(l.query_timestamp_s));
  return queried;
}

void write_ground_truth_loops(std::ostream& out, const std::vector<metrics::GroundTruthLoop>& loops) {
  out << "# ground-truth loops: the query frame revisits the place seen in the match frame (match < query)\n"
         "# indices count the frames from 0\n"
         "# query_timestamp match_timestamp query_index match_index\n";
  char line[128];
  for (const metrics::GroundTruthLoop& l : loops) {
    std::snprintf(line, sizeof line, "%.6f %.6f %lld %lld\n", l.query_timestamp_s, l.match_timestamp_s, l.query_index,
                  l.match_index);
    out << line;
  }
}

std::string loop_evaluation_report(const std::vector<slam::LoopRecord>& loops,
                                   const std::vector<metrics::GroundTruthLoop>& ground_truth,
                                   const GroundTruthPoses& poses, const metrics::LoopEvaluation& e) {
  std::set<std::pair<std::string, std::string>> pairs;
  for (const metrics::GroundTruthLoop& l : ground_truth) {
    pairs.emplace(stamp_text(l.query_timestamp_s), stamp_text(l.match_timestamp_s));
  }
  std::map<std::string, Eigen::Isometry3d> pose_at;
  for (const auto& p : poses) pose_at.emplace(stamp_text(p.first), p.second);
  std::string report;
  char text[256];
  for (const slam::LoopRecord& l : loops) {
    if (!l.accepted) continue;
    const std::string q = stamp_text(l.query_timestamp_s), m = stamp_text(l.match_timestamp_s);
    std::snprintf(text, sizeof text, "loop_accepted query %s match %s keyframes %d %d inliers %d %s", q.c_str(),
                  m.c_str(), l.query_keyframe, l.match_keyframe, l.matched_points,
                  pairs.count({q, m}) > 0 ? "correct" : "wrong");
    report += text;
    const auto pq = pose_at.find(q), pm = pose_at.find(m);
    if (pq != pose_at.end() && pm != pose_at.end()) {
      const double distance_m = (pq->second.translation() - pm->second.translation()).norm();
      const double cosine = pq->second.linear().col(2).dot(pm->second.linear().col(2));
      const double angle_deg = std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI;
      std::snprintf(text, sizeof text, " ground_truth_apart %.3f m %.1f deg", distance_m, angle_deg);
      report += text;
    }
    report += '\n';
  }
  const auto line = [&](const char* name, double value) {
    std::snprintf(text, sizeof text, "%s %.6g\n", name, value);
    report += text;
  };
  line("loop_ground_truth_pairs", static_cast<double>(e.ground_truth_pairs));
  line("loop_correct", static_cast<double>(e.correct_detections));
  line("loop_precision", e.precision);
  line("loop_queries_with_loop", static_cast<double>(e.loop_queries));
  line("loop_query_recall", e.query_recall);
  line("loop_events", static_cast<double>(e.loop_events));
  line("loop_event_recall", e.event_recall);
  return report;
}

}  // namespace run
}  // namespace cge
