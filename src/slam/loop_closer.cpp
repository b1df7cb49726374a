#include "cge/slam/loop_closer.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "cge/opencv/keypoint.hpp"
#include "cge/opencv/mask.hpp"
#include "cge/slam/geometry/descriptor_matching.hpp"
#include "cge/slam/geometry/pnp_ransac.hpp"

namespace cge {
namespace slam {

const char* to_string(LoopScoring scoring) {
  switch (scoring) {
    case LoopScoring::cge:
      return "cge";
    case LoopScoring::bow_only:
      return "bow_only";
    case LoopScoring::combined:
      return "combined";
  }
  return "invalid";
}

LoopScoring loop_scoring_from_string(const std::string& name) {
  if (name == "cge") return LoopScoring::cge;
  if (name == "bow_only") return LoopScoring::bow_only;
  if (name == "combined") return LoopScoring::combined;
  throw std::invalid_argument("loop scoring \"" + name + "\" is not one of cge, bow_only, combined");
}

const char* to_string(LoopReason reason) {
  switch (reason) {
    case LoopReason::accepted:
      return "accepted";
    case LoopReason::no_candidates:
      return "no_candidates";
    case LoopReason::low_score:
      return "low_score";
    case LoopReason::continuity:
      return "continuity";
    case LoopReason::too_few_matches:
      return "too_few_matches";
    case LoopReason::pose_not_robust:
      return "pose_not_robust";
  }
  return "invalid";
}

void LoopCloserSettings::validate() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument("LoopCloserSettings: " + what); };
  if (!(min_common_words_ratio >= 0 && min_common_words_ratio <= 1)) bad("min_common_words_ratio must lie in [0, 1]");
  if (recent_keyframes_excluded < 0) bad("recent_keyframes_excluded must not be negative");
  if (group_size < 0) bad("group_size must not be negative");
  if (!std::isfinite(min_cge_score)) bad("min_cge_score must be finite");
  if (!std::isfinite(min_bow_score)) bad("min_bow_score must be finite");
  if (consistent_keyframes < 1) bad("consistent_keyframes must be at least 1");
  if (verified_members < 1) bad("verified_members must be at least 1");
  if (!(min_group_total_ratio >= 0 && min_group_total_ratio <= 1)) bad("min_group_total_ratio must lie in [0, 1]");
  if (min_matched_points < 3) bad("min_matched_points must be at least 3 (PnP needs 4 points)");
  if (max_descriptor_distance < 0 || max_descriptor_distance > 256) bad("max_descriptor_distance must lie in 0 .. 256");
  if (!(descriptor_ratio > 0 && descriptor_ratio <= 1)) bad("descriptor_ratio must lie in (0, 1]");
  if (!(pnp_reprojection_error_px > 0)) bad("pnp_reprojection_error_px must be positive");
  if (pnp_iterations < 1) bad("pnp_iterations must be at least 1");
  if (!(pnp_confidence > 0 && pnp_confidence < 1)) bad("pnp_confidence must lie in (0, 1)");
}

int choose_verification(const std::vector<LoopDecision>& attempts) {
  // Accepted first, then checks that reached PnP, then the most matched points; earliest on ties.
  auto stage = [](const LoopDecision& d) {
    if (d.accepted) return 2;
    return d.reason == LoopReason::pose_not_robust ? 1 : 0;
  };
  int best = -1;
  for (std::size_t i = 0; i < attempts.size(); ++i) {
    const int index = static_cast<int>(i);
    if (best < 0) {
      best = index;
      continue;
    }
    const LoopDecision& a = attempts[i];
    const LoopDecision& b = attempts[static_cast<std::size_t>(best)];
    if (stage(a) > stage(b) || (stage(a) == stage(b) && a.matched_points > b.matched_points)) best = index;
  }
  return best;
}

std::vector<int> static_feature_rows(const Keyframe& kf) {
  std::vector<int> rows;
  for (std::size_t i = 0; i < kf.labels.size(); ++i) {
    if (kf.labels[i] == FeatureLabel::static_feature) rows.push_back(static_cast<int>(i));
  }
  return rows;
}

namespace {

void check_keyframe(const Keyframe& kf, int width, int height) {
  std::ostringstream where;
  where << "LoopCloser: keyframe " << kf.id << ": ";
  const std::size_t n = kf.keypoints.size();
  opencv::check_orb_descriptors(kf.descriptors, (where.str() + "descriptors").c_str());
  if (static_cast<std::size_t>(kf.descriptors.rows) != n) {
    throw std::invalid_argument(where.str() + std::to_string(kf.descriptors.rows) + " descriptor rows for " +
                                std::to_string(n) + " keypoints");
  }
  if (kf.labels.size() != n) {
    throw std::invalid_argument(where.str() + std::to_string(kf.labels.size()) + " labels for " + std::to_string(n) +
                                " keypoints");
  }
  if (!kf.undistorted_px.empty() && kf.undistorted_px.size() != n) {
    throw std::invalid_argument(where.str() + std::to_string(kf.undistorted_px.size()) + " undistorted positions for " +
                                std::to_string(n) + " keypoints (expected one per keypoint, or none)");
  }
  if (!kf.points_camera_m.empty() && kf.points_camera_m.size() != n) {
    throw std::invalid_argument(where.str() + std::to_string(kf.points_camera_m.size()) + " 3-D points for " +
                                std::to_string(n) + " keypoints (expected one per keypoint, or none)");
  }
  if (!kf.dynamic_mask.empty() &&
      (kf.dynamic_mask.type() != CV_8UC1 || kf.dynamic_mask.cols != width || kf.dynamic_mask.rows != height)) {
    throw std::invalid_argument(where.str() + "dynamic_mask must be empty or CV_8UC1 of " + std::to_string(width) +
                                " x " + std::to_string(height) + " pixels");
  }
}

std::vector<cv::KeyPoint> select_keypoints(const Keyframe& kf, const std::vector<int>& rows) {
  std::vector<cv::KeyPoint> out;
  out.reserve(rows.size());
  for (int r : rows) out.push_back(kf.keypoints[static_cast<std::size_t>(r)]);
  return out;
}

cv::Mat select_rows(const cv::Mat& m, const std::vector<int>& rows) {
  cv::Mat out(static_cast<int>(rows.size()), m.cols, m.type());
  for (std::size_t i = 0; i < rows.size(); ++i) m.row(rows[i]).copyTo(out.row(static_cast<int>(i)));
  return out;
}

bool has_depth(const Keyframe& kf, int row) {
  if (kf.points_camera_m.empty()) return false;
  const Eigen::Vector3d& p = kf.points_camera_m[static_cast<std::size_t>(row)];
  return p.allFinite() && p.z() > 0;
}

}  // namespace

CGESimilarity<double> loop_similarity(const LoopCloserSettings& settings) {
  CGESimilarity<double> similarity;
  similarity.settings = settings.similarity;
  similarity.graph_builder.settings = settings.graph;
  similarity.degree_entropy.settings = settings.degree_entropy;
  similarity.degree_entropy.scaling.kind = settings.exponent_scaling;
  return similarity;
}

Graph<double> own_mask_graph(const Keyframe& kf, const ImageRegion<double>& image,
                             const GraphBuilder<double>& builder) {
  const std::vector<cv::KeyPoint> kp = select_keypoints(kf, static_feature_rows(kf));
  return builder.build(image, kp, kf.dynamic_mask, NoMask{}, kf.instances);
}

LoopCloser::LoopCloser(std::unique_ptr<BowModel> model, const PinholeIntrinsics<double>& camera, int image_width_px,
                       int image_height_px, const LoopCloserSettings& settings)
    : model_(std::move(model)), camera_(camera), settings_(settings) {
  if (!model_) throw std::invalid_argument("LoopCloser: the BoW model is null");
  settings_.validate();
  if (image_width_px < 1 || image_height_px < 1)
    throw std::invalid_argument("LoopCloser: the image size must be positive");
  if (!(camera.fx_px > 0 && camera.fy_px > 0 && std::isfinite(camera.cx_px) && std::isfinite(camera.cy_px))) {
    throw std::invalid_argument("LoopCloser: the camera's focal lengths must be positive and its centre finite");
  }
  image_.width_px = image_width_px;
  image_.height_px = image_height_px;
  similarity_ = loop_similarity(settings_);
}

LoopCloser::LoopCloser(bow::Vocabulary vocabulary, const PinholeIntrinsics<double>& camera, int image_width_px,
                       int image_height_px, const LoopCloserSettings& settings)
    : LoopCloser(std::make_unique<VocabularyBowModel>(std::move(vocabulary)), camera, image_width_px, image_height_px,
                 settings) {}

const LoopCloser::CachedEntropies& LoopCloser::own_entropies(const Keyframe& kf) {
  CachedEntropies& c = cache_.at(static_cast<std::size_t>(kf.id));
  if (c.ready) return c;
  const Graph<double> g = own_mask_graph(kf, image_, similarity_.graph_builder);
  c.has_nodes = g.num_nodes() > 0;
  if (c.has_nodes) c.entropies = similarity_.entropies(g);
  c.ready = true;
  return c;
}

double LoopCloser::cge_score(const Keyframe& current, const Keyframe& other) {
  if (settings_.graph_stability == GraphStability::own_mask) {
    const CachedEntropies& a = own_entropies(current);
    const CachedEntropies& b = own_entropies(other);
    if (!a.has_nodes || !b.has_nodes) return 0;  // nothing stable to compare: no evidence of a loop
    return similarity_.combine(a.entropies, b.entropies, compare_semantics(current.instances, other.instances))
        .similarity;
  }
  const std::vector<cv::KeyPoint> kc = select_keypoints(current, static_feature_rows(current));
  const std::vector<cv::KeyPoint> ko = select_keypoints(other, static_feature_rows(other));
  const Graph<double> gc =
      similarity_.graph_builder.build(image_, kc, current.dynamic_mask, other.dynamic_mask, current.instances);
  const Graph<double> go =
      similarity_.graph_builder.build(image_, ko, other.dynamic_mask, current.dynamic_mask, other.instances);
  if (gc.num_nodes() == 0 || go.num_nodes() == 0) return 0;
  return similarity_
      .combine(similarity_.entropies(gc), similarity_.entropies(go),
               compare_semantics(current.instances, other.instances))
      .similarity;
}

void LoopCloser::geometric_check(const Keyframe& current, const Keyframe& match, LoopDecision& decision) const {
  const std::vector<int> query_rows = static_feature_rows(current);
  std::vector<int> match_rows;
  for (int r : static_feature_rows(match)) {
    if (has_depth(match, r)) match_rows.push_back(r);
  }
  decision.reason = LoopReason::too_few_matches;
  if (query_rows.empty() || match_rows.size() < 2) return;

  // Nearest and second-nearest match row for every query row (Hamming), ratio and distance tests,
  // then one query per match row (the closest; the smaller query index on ties).
  const std::vector<DescriptorPair> pairs_by_row =
      match_descriptors_one_to_one(select_rows(current.descriptors, query_rows),
                                   select_rows(match.descriptors, match_rows), settings_.max_descriptor_distance,
                                   settings_.descriptor_ratio);
  decision.tentative_matches = static_cast<int>(pairs_by_row.size());
  decision.matched_points = decision.tentative_matches;
  if (decision.tentative_matches <= settings_.min_matched_points) return;

  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  std::vector<std::pair<int, int>> pairs;  // (query keypoint, match keypoint)
  for (const DescriptorPair& row_pair : pairs_by_row) {
    const int q = query_rows[static_cast<std::size_t>(row_pair.query)];
    const int m = match_rows[static_cast<std::size_t>(row_pair.train)];
    const Eigen::Vector3d& p = match.points_camera_m[static_cast<std::size_t>(m)];
    object.emplace_back(p.x(), p.y(), p.z());
    image.emplace_back(undistorted_position(current, static_cast<std::size_t>(q)));
    pairs.emplace_back(q, m);
  }
  decision.reason = LoopReason::pose_not_robust;
  PnpRansacSettings pnp;
  pnp.iterations = settings_.pnp_iterations;
  pnp.reprojection_px = settings_.pnp_reprojection_error_px;
  pnp.confidence = settings_.pnp_confidence;
  PnpRansacResult solved = solve_pnp_ransac(object, image, camera_, pnp);
  decision.matched_points = static_cast<int>(solved.inliers.size());
  if (!solved.ok || static_cast<int>(solved.inliers.size()) <= settings_.min_matched_points) return;
  // T_camera_object maps match-camera points into the query camera.
  decision.T_match_query = solved.T_camera_object.inverse();
  std::vector<int>& inliers = solved.inliers;
  std::sort(inliers.begin(), inliers.end());
  decision.inlier_pairs.clear();
  for (int i : inliers) decision.inlier_pairs.push_back(pairs[static_cast<std::size_t>(i)]);
  decision.reason = LoopReason::accepted;
  decision.accepted = true;
}

LoopCloser::Scores::Scores(LoopCloser& closer, const Keyframe& current, const KeyframeDatabaseView& map,
                           const Candidates& candidates)
    : closer_(closer), current_(current), map_(map), bow_score_(candidates.bow_score) {
  for (int c : candidates.ids) best_candidate_bow_ = std::max(best_candidate_bow_, bow(c));
  const LoopCloserSettings& s = closer_.settings_;
  threshold_ = s.scoring == LoopScoring::bow_only ? s.min_bow_score : s.min_cge_score;
}

double LoopCloser::Scores::cge(int id) {
  auto it = cge_memo_.find(id);
  if (it != cge_memo_.end()) return it->second;
  const double s = closer_.cge_score(current_, map_.keyframe(id));
  cge_memo_.emplace(id, s);
  return s;
}

double LoopCloser::Scores::member(int id) {
  const double b = bow(id);
  switch (closer_.settings_.scoring) {
    case LoopScoring::bow_only:
      return b;
    case LoopScoring::combined:
      return best_candidate_bow_ > 0 ? cge(id) * b / best_candidate_bow_ : 0.0;
    case LoopScoring::cge:
      break;
  }
  return cge(id);
}

bool LoopCloser::Scores::passes_gate(int id) {
  const double value = closer_.settings_.scoring == LoopScoring::bow_only ? bow(id) : cge(id);
  return value >= threshold_;
}

LoopCloser::Candidates LoopCloser::query_candidates(const Keyframe& current, const std::vector<BowQueryMatch>& bow,
                                                    const KeyframeDatabaseView& map, LoopDecision& decision) const {
  Candidates out;
  out.excluded.assign(static_cast<std::size_t>(current.id) + 1, 0);
  for (int id = std::max(0, current.id - settings_.recent_keyframes_excluded); id <= current.id; ++id) {
    out.excluded[static_cast<std::size_t>(id)] = 1;
  }
  for (int id : map.covisible_keyframes(current.id, -1)) {
    if (id < 0 || id >= current.id) continue;
    out.excluded[static_cast<std::size_t>(id)] = 1;
    decision.connected_keyframes.push_back(id);
  }
  std::sort(decision.connected_keyframes.begin(), decision.connected_keyframes.end());
  out.bow_score.assign(static_cast<std::size_t>(current.id) + 1, 0.0);
  int best_common = 0;
  for (const BowQueryMatch& m : bow) {
    if (m.keyframe_id < 0 || m.keyframe_id >= current.id) continue;
    out.bow_score[static_cast<std::size_t>(m.keyframe_id)] = m.score;
    if (!out.excluded[static_cast<std::size_t>(m.keyframe_id)]) best_common = std::max(best_common, m.common_words);
  }
  for (const BowQueryMatch& m : bow) {
    if (m.keyframe_id < 0 || m.keyframe_id >= current.id || out.excluded[static_cast<std::size_t>(m.keyframe_id)]) {
      continue;
    }
    if (m.common_words > 0 && m.common_words >= settings_.min_common_words_ratio * best_common) {
      out.ids.push_back(m.keyframe_id);
    }
  }
  std::sort(out.ids.begin(), out.ids.end());
  return out;
}

std::vector<LoopCloser::ScoredGroup> LoopCloser::score_groups(const Keyframe& current, const Candidates& candidates,
                                                              const KeyframeDatabaseView& map, Scores& scores) const {
  std::vector<ScoredGroup> groups;
  for (int c : candidates.ids) {
    ScoredGroup s;
    s.group.members.push_back(c);
    for (int id : map.covisible_keyframes(c, settings_.group_size)) {
      if (id < 0 || id >= current.id || candidates.excluded[static_cast<std::size_t>(id)]) continue;
      if (std::find(s.group.members.begin(), s.group.members.end(), id) == s.group.members.end()) {
        s.group.members.push_back(id);
      }
    }
    for (int id : s.group.members) {
      const double v = scores.member(id);
      s.total += v;
      s.scored_members.emplace_back(v, id);
    }
    // Best score first, the smaller id on ties.
    std::sort(s.scored_members.begin(), s.scored_members.end(),
              [](const std::pair<double, int>& a, const std::pair<double, int>& b) {
                return a.first != b.first ? a.first > b.first : a.second < b.second;
              });
    s.best = s.scored_members.front().second;
    groups.push_back(std::move(s));
  }
  return groups;
}

namespace {

/// Group indices by descending total, the earlier candidate on ties: [0] is the best group, the
/// one whose best member is the match unless geometry picks another.
std::vector<std::size_t> rank_groups_by_total(const std::vector<double>& totals) {
  std::vector<std::size_t> order(totals.size());
  for (std::size_t g = 0; g < order.size(); ++g) order[g] = g;
  std::stable_sort(order.begin(), order.end(), [&totals](std::size_t a, std::size_t b) { return totals[a] > totals[b]; });
  return order;
}

}  // namespace

void LoopCloser::update_consistency(std::vector<ScoredGroup>& groups, Scores& scores) {
  std::vector<Group> next;
  for (ScoredGroup& scored : groups) {
    if (!scores.passes_gate(scored.best)) continue;
    Group grp = scored.group;
    int previous = 0;
    for (const Group& old : consistent_groups_) {
      for (int id : grp.members) {
        if (std::find(old.members.begin(), old.members.end(), id) != old.members.end()) {
          previous = std::max(previous, old.consistency);
          break;
        }
      }
    }
    grp.consistency = previous + 1;
    scored.consistency = grp.consistency;
    next.push_back(std::move(grp));
  }
  consistent_groups_ = std::move(next);
}

std::vector<LoopDecision> LoopCloser::verify_geometry(const Keyframe& current, const KeyframeDatabaseView& map,
                                                      const std::vector<ScoredGroup>& groups,
                                                      const std::vector<std::size_t>& order, Scores& scores) const {
  const ScoredGroup& chosen = groups[order.front()];
  std::vector<LoopDecision> attempts;
  std::vector<int> verified;
  for (std::size_t g : order) {
    const ScoredGroup& scored = groups[g];
    if (scored.consistency < settings_.consistent_keyframes) continue;
    if (!settings_.verify_all_consistent_groups && g != order.front()) continue;
    if (scored.total < settings_.min_group_total_ratio * chosen.total) continue;
    int checked = 0;
    for (const auto& member : scored.scored_members) {
      if (checked == settings_.verified_members) break;
      if (!scores.passes_gate(member.second)) continue;
      ++checked;
      if (std::find(verified.begin(), verified.end(), member.second) != verified.end()) continue;
      verified.push_back(member.second);
      LoopDecision attempt;
      attempt.match_keyframe = member.second;
      geometric_check(current, map.keyframe(member.second), attempt);
      attempts.push_back(std::move(attempt));
    }
  }
  return attempts;
}

void LoopCloser::decide(std::vector<LoopDecision>& attempts, int chosen_best, Scores& scores,
                        LoopDecision& decision) const {
  if (attempts.empty()) {
    decision.reason = scores.passes_gate(chosen_best) ? LoopReason::continuity : LoopReason::low_score;
    return;
  }
  LoopDecision& kept = attempts[static_cast<std::size_t>(choose_verification(attempts))];
  decision.match_keyframe = kept.match_keyframe;
  decision.bow_score = scores.bow(kept.match_keyframe);
  decision.cge_score = scores.cge(kept.match_keyframe);
  decision.matched_points = kept.matched_points;
  decision.tentative_matches = kept.tentative_matches;
  decision.accepted = kept.accepted;
  decision.reason = kept.reason;
  decision.T_match_query = kept.T_match_query;
  decision.inlier_pairs = std::move(kept.inlier_pairs);
  decision.verified_keyframes = static_cast<int>(attempts.size());
}

LoopDecision LoopCloser::process(const Keyframe& current, const KeyframeDatabaseView& map) {
  if (current.id != processed_) {
    throw std::invalid_argument("LoopCloser::process: keyframe id " + std::to_string(current.id) + ", expected " +
                                std::to_string(processed_) + " (one call per keyframe, in id order)");
  }
  check_keyframe(current, static_cast<int>(image_.width_px), static_cast<int>(image_.height_px));
  cache_.resize(static_cast<std::size_t>(processed_) + 1);

  LoopDecision decision;
  decision.query_keyframe = current.id;
  const cv::Mat static_descriptors = select_rows(current.descriptors, static_feature_rows(current));
  const Candidates candidates = query_candidates(current, model_->query(static_descriptors), map, decision);
  decision.candidates = static_cast<int>(candidates.ids.size());
  if (candidates.ids.empty()) {
    consistent_groups_.clear();  // the chain of consistent groups breaks
    decision.reason = LoopReason::no_candidates;
  } else {
    Scores scores(*this, current, map, candidates);
    std::vector<ScoredGroup> groups = score_groups(current, candidates, map, scores);
    std::vector<double> totals;
    for (const ScoredGroup& g : groups) totals.push_back(g.total);
    const std::vector<std::size_t> order = rank_groups_by_total(totals);
    // The best group's best member is the match unless a verified one replaces it.
    const int chosen_best = groups[order.front()].best;
    decision.match_keyframe = chosen_best;
    decision.bow_score = scores.bow(chosen_best);
    decision.cge_score = scores.cge(chosen_best);
    update_consistency(groups, scores);
    std::vector<LoopDecision> attempts = verify_geometry(current, map, groups, order, scores);
    decide(attempts, chosen_best, scores, decision);
  }
  model_->add(current.id, static_descriptors);
  ++processed_;
  return decision;
}

}  // namespace slam
}  // namespace cge
