#pragma once
// LoopCloser: loop detection and verification over keyframes (docs/METHOD.md section 7, steps 1-4;
// step 5, the correction, belongs to the optimisers). process() is called once per new keyframe, in
// id order; it keeps a BoW entry and cached graph entropies of every keyframe it has seen.
//
// Steps for the current keyframe K (docs/LOOP_CLOSING.md):
//  1. Candidates: keyframes sharing words with K (BowModel::query), neither covisible with K nor
//     among the `recent_keyframes_excluded` keyframes before it, with at least
//     `min_common_words_ratio` of the best such keyframe's common-word count.
//  2. Groups: each candidate with its `group_size` best covisible keyframes (the excluded ones left
//     out).
//  3. Scores: every group member against K: S_sum of CGESimilarity (mode cge), the BoW score
//     (bow_only), or S_sum times the BoW score relative to the best candidate's (combined). Each
//     group keeps its total and its best member; the best member of the best-total group is the
//     match; it must reach the mode's threshold (else low_score).
//  4. Continuity: a group is consistent with an earlier one when they share a keyframe; a group
//     is verifiable only when the groups of `consistent_keyframes` consecutive keyframes (K
//     included) passed step 3 and chain (ORB-SLAM2's consistent groups). No verifiable group: the
//     best group's reason (low_score or continuity).
//  5. Geometry, for every verifiable group (ORB-SLAM2 verifies every consistent candidate) whose
//     total is at least `min_group_total_ratio` of the best group's, best total first, and within
//     it its `verified_members` best members that pass the gate: static
//     features of K matched to static features with depth of the member by descriptor; more than
//     `min_matched_points` matches (else too_few_matches); PnP RANSAC of the member's 3-D points
//     (points_camera_m) to K's pixels; more than `min_matched_points` inliers (else
//     pose_not_robust). The match is the verified member with the most inliers
//     (choose_verification): the closest view of the place; T_match_query is its pose.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "cge/bow/vocabulary.hpp"
#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/entropy/cge_similarity.hpp"
#include "cge/slam/bow_model.hpp"
#include "cge/slam/keyframe.hpp"
#include "cge/slam/keyframe_database_view.hpp"

namespace cge {
namespace slam {

/// What decides among the candidates (step 3).
enum class LoopScoring {
  cge,       ///< BoW proposes candidates, CGE's S_sum decides (the paper)
  bow_only,  ///< the BoW score decides (ORB-SLAM2-like; for comparison)
  combined,  ///< S_sum x (BoW score / best candidate's BoW score)
};

/// "cge", "bow_only", "combined".
const char* to_string(LoopScoring scoring);
/// The inverse; throws std::invalid_argument naming the known values.
LoopScoring loop_scoring_from_string(const std::string& name);

/// Which dynamic masks decide a keypoint's stability in the frame graphs.
enum class GraphStability {
  own_mask,    ///< the keyframe's own mask only: one graph per keyframe, computed once and cached
  both_masks,  ///< own and partner's mask (docs/METHOD.md section 3, exact): two graphs per pair
};

struct LoopCloserSettings {
  /// Step 3 ranking. Default combined: measured better than cge on the loop presets
  /// (docs/LOOP_CLOSING.md); cge is the paper's ranking, bow_only the baseline.
  LoopScoring scoring = LoopScoring::combined;
  /// Step 1: candidates need at least this fraction of the best common-word count (ORB-SLAM2: 0.8).
  double min_common_words_ratio = 0.8;
  /// Step 1: the keyframes with ids in [K - this, K) are never candidates (too recent to be a loop;
  /// ours, ORB-SLAM2's count of 10 keyframes, which it waits after a loop).
  int recent_keyframes_excluded = 10;
  /// Step 2: covisible keyframes added to each candidate's group (ORB-SLAM2's 10 best covisible; the
  /// paper gives no value).
  int group_size = 10;
  /// Step 3, modes cge and combined: least S_sum of the match. 0.5 loses no true loop on the loop
  /// presets while 0.8 already loses some (S_sum barely separates loops; geometry does): see
  /// docs/LOOP_CLOSING.md.
  double min_cge_score = 0.5;
  /// Step 3, mode bow_only: least BoW L1 score of the match.
  double min_bow_score = 0.05;
  /// Step 4: consecutive keyframes (the current one included) whose groups must chain; 1 disables
  /// (ORB-SLAM2's consistency threshold 3; the paper gives no value).
  int consistent_keyframes = 3;
  /// Step 5: members of each verifiable group checked geometrically, best step-3 scores first; the
  /// one with the most PnP inliers is the match. The best-scored member is often a neighbouring,
  /// overlapping view rather than the closest one (docs/LOOP_CLOSING.md); 1 checks only the best.
  int verified_members = 3;
  /// Step 5: verify every group that passed steps 3 and 4, not only the best-total one (ORB-SLAM2
  /// verifies every consistent candidate); false checks the best group alone (when it is
  /// verifiable).
  bool verify_all_consistent_groups = true;
  /// Step 5: only groups whose step-3 total reaches this fraction of the best group's total are
  /// verified (ORB-SLAM2 retains groups above 0.75 of the best accumulated score), in [0, 1]; bounds
  /// the geometric checks, which otherwise cover most of the map when most keyframes share words.
  double min_group_total_ratio = 0.75;
  /// Step 5: Num_th, the matches and PnP inliers needed are MORE than this (paper: 40).
  int min_matched_points = 40;
  /// Step 5: largest Hamming distance of a descriptor match, bits (ORB-SLAM2's TH_LOW: 50).
  int max_descriptor_distance = 50;
  /// Step 5: Lowe's ratio, best distance < ratio x second best (ORB-SLAM2 uses 0.75 for BoW search).
  double descriptor_ratio = 0.75;
  /// Step 5: PnP RANSAC inlier threshold, pixels of reprojection error.
  double pnp_reprojection_error_px = 4.0;
  /// Step 5: PnP RANSAC iterations.
  int pnp_iterations = 300;
  /// Step 5: PnP RANSAC confidence.
  double pnp_confidence = 0.999;
  /// Graph stability masks (GraphStability); own_mask caches each keyframe's entropies.
  GraphStability graph_stability = GraphStability::own_mask;
  /// Settings of the graph construction and the similarity (cge/graph, cge/entropy).
  GraphBuilderSettings<double> graph;
  CGESimilaritySettings<double> similarity;
  DegreeDegreeSettings<double> degree_entropy;
  /// Exponent scaling of the degree-degree entropy: normalised_mean by default (raw, the paper's,
  /// collapses the entropy on SLAM-sized graphs and ranked worse on the loop presets).
  ScalingKind exponent_scaling = ScalingKind::normalised_mean;

  /// Throws std::invalid_argument naming the first field out of range.
  void validate() const;
};

/// Why a keyframe was (not) accepted; names as loops.csv spells them (to_string).
enum class LoopReason { accepted, no_candidates, low_score, continuity, too_few_matches, pose_not_robust };
const char* to_string(LoopReason reason);

struct LoopDecision {
  int query_keyframe = -1;
  int match_keyframe = -1;  ///< -1 when there was no candidate
  double bow_score = 0;     ///< BoW score of the match against the query (0 without a match)
  double cge_score = 0;     ///< S_sum of the match against the query (computed in every mode)
  /// Descriptor matches while the geometric check ran: PnP inliers when PnP ran, else the tentative
  /// matches; 0 before step 5.
  int matched_points = 0;
  int tentative_matches = 0;  ///< descriptor matches before RANSAC
  bool accepted = false;
  LoopReason reason = LoopReason::no_candidates;
  int candidates = 0;  ///< candidates after step 1
  /// Geometric checks run in step 5 (0 when no group was verifiable).
  int verified_keyframes = 0;
  /// Keyframes covisible with the query when it was processed, ascending: already connected to it,
  /// hence never candidates (a loop to them is closed already). For the evaluation (loops.csv).
  std::vector<int> connected_keyframes;
  /// Pose of the query camera in the match camera's frame (valid when PnP succeeded).
  Eigen::Isometry3d T_match_query = Eigen::Isometry3d::Identity();
  /// PnP inliers: (query keypoint index, match keypoint index).
  std::vector<std::pair<int, int>> inlier_pairs;
};

class LoopCloser {
 public:
  /// `model` is the BoW policy (not null); `camera` the intrinsics the keypoints were detected with;
  /// the image size (pixels) defines the graphs' region.
  LoopCloser(std::unique_ptr<BowModel> model, const PinholeIntrinsics<double>& camera, int image_width_px,
             int image_height_px, const LoopCloserSettings& settings = {});
  /// Our model over `vocabulary`.
  LoopCloser(bow::Vocabulary vocabulary, const PinholeIntrinsics<double>& camera, int image_width_px,
             int image_height_px, const LoopCloserSettings& settings = {});

  /// Detects and verifies a loop for `current` (its id must equal processed_count()), then adds it.
  /// Reads earlier keyframes and covisibility through `map` (current must be map.keyframe(current.id)
  /// or a copy of it). Throws std::invalid_argument for a keyframe whose per-keypoint vectors
  /// disagree in size, descriptors that are not 32-byte CV_8UC1 rows, or an id out of order.
  LoopDecision process(const Keyframe& current, const KeyframeDatabaseView& map);

  int processed_count() const { return processed_; }
  /// The BoW model's matches of `descriptors` among every keyframe processed so far (for
  /// relocalisation over the whole map); sorted by ascending keyframe id.
  std::vector<BowQueryMatch> query_bow(const cv::Mat& descriptors) const { return model_->query(descriptors); }
  const LoopCloserSettings& settings() const { return settings_; }

 private:
  struct Group {
    std::vector<int> members;
    int consistency = 0;
  };
  /// Step 1's result.
  struct Candidates {
    std::vector<int> ids;           ///< ascending
    std::vector<char> excluded;     ///< by keyframe id: too recent or covisible with the query
    std::vector<double> bow_score;  ///< by keyframe id: the BoW score against the query, 0 when not returned
  };
  /// Steps 2 and 3 for one candidate.
  struct ScoredGroup {
    Group group;
    std::vector<std::pair<double, int>> scored_members;  ///< (step-3 score, id), best first
    double total = 0;
    int best = -1;
    int consistency = 0;  ///< step 4; 0 when the group's best member fails the gate
  };
  /// The scores of one query against its candidates and their groups; S_sum computed once per
  /// keyframe, on first use.
  class Scores {
   public:
    Scores(LoopCloser& closer, const Keyframe& current, const KeyframeDatabaseView& map,
           const Candidates& candidates);
    double bow(int id) const { return bow_score_[static_cast<std::size_t>(id)]; }
    double cge(int id);
    /// The step-3 ranking value of the scoring mode.
    double member(int id);
    /// The step-3 gate: the BoW score in bow_only mode, S_sum otherwise (also in combined mode,
    /// whose product only ranks), at least the mode's threshold.
    bool passes_gate(int id);

   private:
    LoopCloser& closer_;
    const Keyframe& current_;
    const KeyframeDatabaseView& map_;
    const std::vector<double>& bow_score_;
    double best_candidate_bow_ = 0;
    double threshold_ = 0;
    std::map<int, double> cge_memo_;
  };
  struct CachedEntropies {
    bool ready = false;
    bool has_nodes = false;
    GraphEntropies<double> entropies;
  };

  double cge_score(const Keyframe& current, const Keyframe& other);
  const CachedEntropies& own_entropies(const Keyframe& kf);
  /// Step 1: keyframes sharing enough words with the query, neither recent nor covisible with it
  /// (those are connected already: a loop to them closes nothing). Fills connected_keyframes.
  Candidates query_candidates(const Keyframe& current, const std::vector<BowQueryMatch>& bow,
                              const KeyframeDatabaseView& map, LoopDecision& decision) const;
  /// Steps 2 and 3: each candidate with its covisible keyframes, every member scored (the graph
  /// entropy S_sum, the BoW score or both, by mode): one view scores noisily, a group of
  /// neighbouring views of the same place less so.
  std::vector<ScoredGroup> score_groups(const Keyframe& current, const Candidates& candidates,
                                        const KeyframeDatabaseView& map, Scores& scores) const;
  /// Step 4: the groups whose best member passes the gate chain with the last query's groups when
  /// they share a keyframe; a single query's match is often chance, a place seen again over
  /// consecutive keyframes is not.
  void update_consistency(std::vector<ScoredGroup>& groups, Scores& scores);
  /// Step 5: PnP on the best members of every verifiable group (`order`: groups best total first);
  /// each keyframe checked once. Scores only rank; geometry decides whether the place is the same.
  std::vector<LoopDecision> verify_geometry(const Keyframe& current, const KeyframeDatabaseView& map,
                                            const std::vector<ScoredGroup>& groups,
                                            const std::vector<std::size_t>& order, Scores& scores) const;
  /// The outcome: the attempt choose_verification keeps, or, without attempts, why the best group
  /// (best member `chosen_best`) stopped: low_score when it failed the gate, else continuity.
  void decide(std::vector<LoopDecision>& attempts, int chosen_best, Scores& scores, LoopDecision& decision) const;
  /// Step 5 for one member; fills the geometric fields of `decision` (reason, matches, pose, inliers).
  void geometric_check(const Keyframe& current, const Keyframe& match, LoopDecision& decision) const;

  std::unique_ptr<BowModel> model_;
  PinholeIntrinsics<double> camera_;
  ImageRegion<double> image_;
  LoopCloserSettings settings_;
  CGESimilarity<double> similarity_;
  std::vector<CachedEntropies> cache_;
  std::vector<Group> consistent_groups_;
  int processed_ = 0;
};

/// The geometric check step 5 keeps among `attempts` (in verification order): the accepted one with
/// the most PnP inliers (matched_points), the earliest on ties; when none was accepted, the one that
/// came closest: pose_not_robust (PnP ran) before too_few_matches, then the most matched_points, the
/// earliest on ties. -1 for no attempts.
int choose_verification(const std::vector<LoopDecision>& attempts);

/// Rows of the keyframe's static features (labels == static_feature), ascending.
std::vector<int> static_feature_rows(const Keyframe& kf);

/// The CGESimilarity a LoopCloser with `settings` scores with (graph builder, degree-degree entropy
/// with the settings' exponent scaling, edge entropy): for studies that must measure exactly what
/// loop closing uses (examples/cge_loop_study.cpp).
CGESimilarity<double> loop_similarity(const LoopCloserSettings& settings);

/// The graph a LoopCloser scores `kf` by in own_mask mode: its static keypoints, its own dynamic
/// mask and its semantic instances, in `image`.
Graph<double> own_mask_graph(const Keyframe& kf, const ImageRegion<double>& image, const GraphBuilder<double>& builder);

}  // namespace slam
}  // namespace cge
