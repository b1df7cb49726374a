#include "cge/slam/system.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "cge/opencv/keypoint.hpp"
#include "cge/slam/local_mapping.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/moving_keypoints.hpp"

namespace cge {
namespace slam {

const char* to_string(Stage stage) {
  switch (stage) {
    case Stage::segmentation:
      return "segmentation";
    case Stage::features:
      return "features";
    case Stage::dynamic_filter:
      return "dynamic_filter";
    case Stage::tracking:
      return "tracking";
    case Stage::keyframe:
      return "keyframe";
    case Stage::local_mapping:
      return "local_mapping";
    case Stage::loop_closing:
      return "loop_closing";
    case Stage::optimisation:
      return "optimisation";
    case Stage::total:
      return "total";
  }
  return "invalid";
}

namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

double& time_of(FrameRecord& r, Stage s) { return r.times_ms[static_cast<std::size_t>(s)]; }

}  // namespace

System::System(const SystemSettings& settings, const PinholeIntrinsics<double>& intrinsics,
               std::unique_ptr<InstanceSegmenter> segmenter)
    : settings_(settings),
      intrinsics_(intrinsics),
      segmenter_(std::move(segmenter)),
      frame_maker_(settings, intrinsics),
      tracker_(settings.tracker, intrinsics, settings.frame.orb.scale_factor),
      keyframe_policy_(keyframe_policy_of(settings.mode), settings.patch_keyframes, settings.orbslam2_keyframes),
      loop_correction_(settings.loop_correction, intrinsics, settings.frame.orb.scale_factor) {}

System::~System() = default;
System::System(System&&) noexcept = default;
System& System::operator=(System&&) noexcept = default;

void System::set_loop_closer(std::unique_ptr<LoopCloser> loop_closer) {
  if (map_.keyframe_count() > 0) throw std::logic_error("System::set_loop_closer: the map has keyframes already");
  loop_closer_ = std::move(loop_closer);
  if (loop_closer_ == nullptr) {
    tracker_.set_relocalisation_candidates(nullptr);
    return;
  }
  // Relocalisation over the whole map: keyframes by BoW score of the frame's static features, best
  // first. The closer's object outlives moves of the System (owned through a unique_ptr).
  const LoopCloser* closer = loop_closer_.get();
  tracker_.set_relocalisation_candidates([closer](const Frame& frame) {
    cv::Mat static_descriptors;
    for (int i = 0; i < frame.size(); ++i) {
      if (frame.is_static(i)) static_descriptors.push_back(frame.descriptors.row(i));
    }
    std::vector<BowQueryMatch> matches;
    if (!static_descriptors.empty()) matches = closer->query_bow(static_descriptors);
    std::stable_sort(matches.begin(), matches.end(),
                     [](const BowQueryMatch& a, const BowQueryMatch& b) { return a.score > b.score; });
    std::vector<int> ids;
    for (const BowQueryMatch& m : matches) ids.push_back(m.keyframe_id);
    return ids;
  });
}

const FrameRecord& System::process(const FrameInput& input) {
  std::vector<SegmentedInstance> instances;
  double segmentation_ms = 0;
  if (uses_masks(settings_.mode) && segmenter_ != nullptr) {
    const auto start = Clock::now();
    instances = segmenter_->segment(FrameImage{input.bgr, input.stem});
    segmentation_ms = elapsed_ms(start);
  }
  return process(input, instances, segmentation_ms);
}

const FrameRecord& System::process(const FrameInput& input, const std::vector<SegmentedInstance>& instances,
                                   double segmentation_ms) {
  const auto start = Clock::now();
  if (!records_.empty() && input.index <= records_.back().index) {
    throw std::invalid_argument("System::process: frame index " + std::to_string(input.index) +
                                " is not greater than the previous " + std::to_string(records_.back().index));
  }
  FrameRecord record;
  record.index = input.index;
  record.timestamp_s = input.timestamp_s;
  image_size_ = input.bgr.size();
  time_of(record, Stage::segmentation) = segmentation_ms;

  auto t = Clock::now();
  Frame frame = frame_maker_.extract(input.index, input.timestamp_s, input.bgr, input.depth);
  time_of(record, Stage::features) = elapsed_ms(t);

  t = Clock::now();
  frame_maker_.label(frame, instances);
  time_of(record, Stage::dynamic_filter) = elapsed_ms(t);
  if (settings_.keep_keyframe_images) {
    // Class image for the semantic maps; later instances overwrite earlier ones where masks overlap.
    frame.class_labels = cv::Mat::zeros(input.bgr.size(), CV_16UC1);
    for (const SegmentedInstance& instance : instances) {
      frame.class_labels.setTo(cv::Scalar(instance.class_id + 1), instance.mask);
    }
  }
  record.keypoints = frame.size();
  record.dynamic_by_mask = frame.count(FeatureLabel::dynamic_by_mask);
  record.dynamic_by_mad = frame.count(FeatureLabel::dynamic_by_mad);
  record.instances = static_cast<int>(frame.instances.size());
  if (!input.moving_mask.empty()) {
    if (input.moving_mask.type() != CV_8UC1 || input.moving_mask.size() != input.bgr.size()) {
      throw std::invalid_argument("System::process: frame " + std::to_string(input.index) +
                                  ": the moving mask is not CV_8UC1 of the image's size");
    }
    const MovingKeypointCounts moving = count_moving_keypoints(frame.keypoints, frame.labels, input.moving_mask);
    record.moving_keypoints = moving.moving_keypoints;
    record.moving_kept = moving.moving_kept;
  }

  // The rounds of the pending local BA due in this frame, before it is tracked: the frame is
  // tracked in the map as those rounds leave it (LocalMappingSettings::ba_from_next_frame).
  advance_local_mapping(record, settings_.local_mapping.ba_rounds_per_frame);

  t = Clock::now();
  TrackResult track = tracker_.track(frame, map_);
  time_of(record, Stage::tracking) = elapsed_ms(t);
  if (track.has_pose()) {
    // Map-point culling's found ratio: predicted in view, and matched as an inlier.
    for (const std::int64_t p : track.visible_map_points) map_.increase_visible(p);
    for (const std::int64_t p : track.map_point_ids) {
      if (p >= 0) map_.increase_found(p);
    }
  }
  record.state = track.state;
  record.matches = track.matches;
  record.inliers = track.inliers;
  record.T_world_camera = track.T_world_camera;
  records_.push_back(record);
  const std::size_t index = records_.size() - 1;

  t = Clock::now();
  const auto triggered_ms = [&] {
    return time_of(records_[index], Stage::local_mapping) + time_of(records_[index], Stage::loop_closing) +
           time_of(records_[index], Stage::optimisation);
  };
  const double triggered_before_ms = triggered_ms();
  if (track.has_pose()) decide_keyframe(frame, track, index);
  // Keyframe time excludes the local mapping, loop closing and optimisation it triggered (timed on
  // their own).
  FrameRecord& r = records_[index];
  // With no keyframe inserted, nothing has moved the reference since tracking. (An insertion has
  // set the relation already, before its local BA and loop correction: see insert_keyframe.)
  if (r.has_pose() && r.reference_keyframe < 0 && tracker_.reference_keyframe() >= 0) {
    keep_relative_to(index, tracker_.reference_keyframe());
  }
  time_of(r, Stage::keyframe) = elapsed_ms(t) - (triggered_ms() - triggered_before_ms);
  time_of(r, Stage::total) = elapsed_ms(start) + segmentation_ms;
  return r;
}

void System::decide_keyframe(Frame& frame, TrackResult& track, std::size_t record) {
  if (track.state == TrackingState::initialised) {
    keyframe_policy_.reset();
    pending_.clear();
  }
  const PatchKeyframeSelector<double> grid_source(settings_.patch_keyframes);
  std::vector<cv::KeyPoint> static_keypoints;
  for (int i = 0; i < frame.size(); ++i) {
    if (frame.is_static(i)) static_keypoints.push_back(frame.keypoints[static_cast<std::size_t>(i)]);
  }
  ImageRegion<double> image;
  image.width_px = frame.image_size.width;
  image.height_px = frame.image_size.height;
  FrameSummary<double> summary =
      grid_source.summarise(frame.index, image, static_keypoints, frame.instances, track.inliers);
  // Close points (the baseline's close-point rule): static keypoints with a close depth, tracked or not.
  summary.tracked_close_points = 0;
  summary.untracked_close_points = 0;
  for (int i = 0; i < frame.size(); ++i) {
    if (!frame.is_static(i) || !frame.has_depth(i)) continue;
    if (frame.points_camera_m[static_cast<std::size_t>(i)].z() >= settings_.frame.close_depth_m) continue;
    const bool tracked = track.map_point_ids[static_cast<std::size_t>(i)] >= 0;
    (tracked ? summary.tracked_close_points : summary.untracked_close_points) += 1;
  }
  // The baseline compares with the reference keyframe's well-observed points, as they are now.
  const int reference = tracker_.reference_keyframe();
  if (keyframe_policy_.reference_id() != kNoFrame && reference >= 0) {
    const MappingSettings& m = settings_.mapping;
    const int min_obs = map_.keyframe_count() <= 2 ? std::min(2, m.reference_min_observations)
                                                   : m.reference_min_observations;
    int well_observed = 0;
    for (const std::int64_t p : map_.keyframe(reference).map_point_ids) {
      well_observed += p >= 0 && weighted_observations(map_, map_.map_point(p)) >= min_obs;
    }
    keyframe_policy_.set_reference_tracked_points(well_observed);
  }
  const KeyframeDecision<double> decision = keyframe_policy_.step(summary);
  if (track.state == TrackingState::initialised && decision.keyframe_id != frame.index) {
    throw std::logic_error("System: the keyframe policy did not take the first frame");
  }
  apply_decision(decision, &frame, &track, record);
}

void System::apply_decision(const KeyframeDecision<double>& decision, Frame* current, TrackResult* track,
                            std::size_t record) {
  if (decision.inserts_keyframe()) {
    const char* rule = to_string(decision.rule);
    const std::size_t current_record = current != nullptr ? record : kNoRecord;
    if (current != nullptr && decision.keyframe_id == current->index) {
      insert_keyframe(*current, *track, record, rule, current_record);
    } else {
      const auto it = std::find_if(pending_.begin(), pending_.end(),
                                   [&](const Pending& p) { return p.frame.index == decision.keyframe_id; });
      if (it == pending_.end()) {
        throw std::logic_error("System: the keyframe policy chose frame " + std::to_string(decision.keyframe_id) +
                               ", which is not pending");
      }
      insert_keyframe(it->frame, it->track, it->record, rule, current_record);
    }
  }
  const std::vector<std::int64_t> keep = keyframe_policy_.pending_ids();
  pending_.erase(std::remove_if(pending_.begin(), pending_.end(),
                                [&](const Pending& p) {
                                  return std::find(keep.begin(), keep.end(), p.frame.index) == keep.end();
                                }),
                 pending_.end());
  if (current != nullptr && decision.keep_current) pending_.push_back(Pending{*current, *track, record});
}

int System::insert_keyframe(const Frame& frame, const TrackResult& track, std::size_t record, const char* rule,
                            std::size_t current_record) {
  // The previous keyframe's BA ends before the map changes.
  advance_local_mapping(records_.back(), kAllRounds);
  Keyframe kf;
  kf.frame_index = frame.index;
  kf.timestamp_s = frame.timestamp_s;
  kf.T_world_camera = track.T_world_camera;
  kf.keypoints = frame.keypoints;
  kf.descriptors = frame.descriptors.clone();
  kf.labels = frame.labels;
  kf.undistorted_px = frame.undistorted_px;
  kf.points_camera_m = frame.points_camera_m;
  kf.instances = frame.instances;
  kf.dynamic_mask = frame.dynamic_mask;
  if (settings_.keep_keyframe_images) {
    kf.bgr = frame.bgr.clone();
    kf.depth_m = frame.depth_m;
    kf.class_labels = frame.class_labels;
  }
  const int id = map_.add_keyframe(std::move(kf));
  for (int i = 0; i < frame.size(); ++i) {
    // A point erased since the frame was tracked (a BA finished above culled it) is not observed.
    const std::int64_t tracked = track.map_point_ids[static_cast<std::size_t>(i)];
    if (tracked >= 0 && !map_.map_point(tracked).bad) map_.add_observation(tracked, id, i);
  }
  // New points from depth, nearest first, every untracked static keypoint under max_new_point_depth_m;
  // with only_close_new_points, far ones only until the keyframe observes min_new_points (ORB-SLAM2's
  // RGB-D rule).
  std::vector<std::pair<double, int>> by_depth;  // (depth, keypoint), ties by keypoint
  for (int i = 0; i < frame.size(); ++i) {
    if (!frame.is_static(i) || !frame.has_depth(i)) continue;
    const double z = frame.points_camera_m[static_cast<std::size_t>(i)].z();
    if (z < settings_.mapping.max_new_point_depth_m) by_depth.emplace_back(z, i);
  }
  std::sort(by_depth.begin(), by_depth.end());
  int observed = 0;
  for (const auto& [z, i] : by_depth) {
    if (settings_.mapping.only_close_new_points && z > settings_.frame.close_depth_m &&
        observed > settings_.mapping.min_new_points) {
      break;
    }
    ++observed;
    if (track.map_point_ids[static_cast<std::size_t>(i)] >= 0) continue;  // tracked: observed already
    const Eigen::Vector3d& p_camera = frame.points_camera_m[static_cast<std::size_t>(i)];
    const std::int64_t point = map_.add_map_point(track.T_world_camera * p_camera, frame.descriptors.row(i), id);
    map_.add_observation(point, id, i);
    recent_points_.push_back(point);
  }
  tracker_.set_reference_keyframe(id);
  FrameRecord& r = records_[record];
  r.keyframe_id = id;
  r.keyframe_rule = rule;
  // The poses of the keyframe's frame and of the frame being processed, against the keyframe's
  // pose as inserted: both were tracked in the map as it is before the local BA and a loop
  // correction move the keyframe (taken after them, a correction's whole shift would end up in the
  // relative pose, and the frame would not follow it).
  keep_relative_to(record, id);
  if (current_record != kNoRecord && current_record != record) keep_relative_to(current_record, id);
  after_keyframe_inserted(id);
  return id;
}

void System::keep_relative_to(std::size_t record, int keyframe_id) {
  FrameRecord& r = records_[record];
  if (!r.has_pose()) return;
  r.reference_keyframe = keyframe_id;
  r.T_reference_camera = map_.keyframe(keyframe_id).T_world_camera.inverse() * r.T_world_camera;
}

MapMaintenanceSettings System::maintenance_settings() const {
  MapMaintenanceSettings maintenance = settings_.local_mapping.maintenance;
  maintenance.close_depth_m = settings_.frame.close_depth_m;  // the frame's close/far rule
  return maintenance;
}

void System::local_mapping(int keyframe_id) {
  const LocalMappingSettings& lm = settings_.local_mapping;
  const MapMaintenanceSettings maintenance = maintenance_settings();
  const double scale = settings_.frame.orb.scale_factor;
  if (lm.cull_map_points) cull_recent_map_points(map_, recent_points_, keyframe_id, maintenance);
  if (lm.triangulate_points) {
    const TriangulationReport made = triangulate_new_points(map_, keyframe_id, intrinsics_, scale, maintenance);
    recent_points_.insert(recent_points_.end(), made.created.begin(), made.created.end());
  }
  if (lm.fuse_map_points) fuse_map_points(map_, keyframe_id, intrinsics_, image_size_, scale, maintenance);
  if (lm.bundle_adjustment) {
    local_ba_ = std::make_unique<LocalBundleAdjustment>(map_, keyframe_id, intrinsics_, lm, scale);
  }
}

void System::advance_local_mapping(FrameRecord& charged, int max_rounds) {
  if (local_ba_ == nullptr) return;
  const auto start = Clock::now();
  const int iterations_per_frame = settings_.local_mapping.ba_iterations_per_frame;
  if (iterations_per_frame > 0 && max_rounds != kAllRounds) {
    // Each slice uses at least one iteration or ends a round, so this loop is bounded.
    int left = iterations_per_frame;
    while (left > 0 && !local_ba_->done()) left -= local_ba_->solve_next_slice(map_, left);
  } else if (max_rounds >= local_ba_->rounds_left()) {
    local_ba_->solve_remaining_rounds(map_);  // one write into the map
  } else {
    for (int i = 0; i < max_rounds; ++i) local_ba_->solve_next_round(map_);
  }
  time_of(charged, Stage::local_mapping) += elapsed_ms(start);
  if (!local_ba_->done()) return;
  const int keyframe_id = local_ba_->keyframe_id();
  local_ba_.reset();
  complete_keyframe(keyframe_id, charged);
}

void System::after_keyframe_inserted(int keyframe_id) {
  const auto start_local = Clock::now();
  local_mapping(keyframe_id);
  time_of(records_.back(), Stage::local_mapping) += elapsed_ms(start_local);
  if (local_ba_ == nullptr) {
    complete_keyframe(keyframe_id, records_.back());
  } else if (!settings_.local_mapping.ba_from_next_frame || local_ba_->done()) {
    // Otherwise the next frame starts the rounds, before it is tracked (process).
    advance_local_mapping(records_.back(), settings_.local_mapping.ba_rounds_per_frame);
  }
}

void System::complete_keyframe(int keyframe_id, FrameRecord& charged) {
  const LocalMappingSettings& lm = settings_.local_mapping;
  if (lm.cull_keyframes) {
    const auto start_cull = Clock::now();
    cull_redundant_keyframes(map_, keyframe_id, maintenance_settings());
    // The tracker's local map is centred on a live keyframe.
    int reference = tracker_.reference_keyframe();
    while (reference >= 0 && map_.keyframe(reference).culled) reference = map_.keyframe(reference).parent;
    tracker_.set_reference_keyframe(reference);
    time_of(charged, Stage::local_mapping) += elapsed_ms(start_cull);
  }
  // Loop closing (docs/METHOD.md section 7): the closer reads map_ (a KeyframeDatabaseView) and
  // its decision becomes a LoopRecord. The correction of an accepted loop (pose-graph
  // optimisation, then bundle adjustment, through map_.set_keyframe_pose / set_map_point_position)
  // follows, timed as the optimisation stage.
  if (loop_closer_ == nullptr) return;
  const auto start = Clock::now();
  const Keyframe& kf = map_.keyframe(keyframe_id);
  const LoopDecision d = loop_closer_->process(kf, map_);
  LoopRecord r;
  r.query_keyframe = keyframe_id;
  r.query_timestamp_s = kf.timestamp_s;
  r.match_keyframe = d.match_keyframe;
  if (d.match_keyframe >= 0) r.match_timestamp_s = map_.keyframe(d.match_keyframe).timestamp_s;
  r.bow_score = d.bow_score;
  r.cge_score = d.cge_score;
  r.matched_points = d.matched_points;
  r.accepted = d.accepted;
  r.reason = to_string(d.reason);
  r.tentative_matches = d.tentative_matches;
  r.verified_keyframes = d.verified_keyframes;
  r.connected_keyframes = d.connected_keyframes;
  loops_.push_back(std::move(r));
  time_of(charged, Stage::loop_closing) += elapsed_ms(start);

  if (!d.accepted || !settings_.loop_correction.enabled) return;
  loop_correction_.add_loop(LoopEdge{d.match_keyframe, keyframe_id, d.T_match_query});
  if (!loop_correction_.due(keyframe_id)) return;  // its edge joins the next correction
  const auto start_optimisation = Clock::now();
  const LoopCorrectionReport corrected = loop_correction_.correct(map_, keyframe_id);
  tracker_.apply_map_correction(corrected.T_corrected_old);
  time_of(charged, Stage::optimisation) += elapsed_ms(start_optimisation);
}

void System::finish() {
  const KeyframeDecision<double> decision = keyframe_policy_.flush();
  apply_decision(decision, nullptr, nullptr, 0);
  pending_.clear();
  if (!records_.empty()) advance_local_mapping(records_.back(), kAllRounds);
}

Eigen::Isometry3d System::pose_of(const FrameRecord& record) const {
  if (record.reference_keyframe < 0) return record.T_world_camera;
  return map_.keyframe(record.reference_keyframe).T_world_camera * record.T_reference_camera;
}

}  // namespace slam
}  // namespace cge
