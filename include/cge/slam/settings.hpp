#pragma once
// Settings of the reference pipeline's tracking front (Frame, Tracker, System): every threshold with
// its unit and default. Defaults marked "ORB-SLAM2" are that system's TUM RGB-D values; the rest
// are ours, chosen on the synthetic walking sequences (docs in the pipeline's report).
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "cge/ceres/bundle_adjustment.hpp"
#include "cge/ceres/pose_graph.hpp"
#include "cge/ceres/pose_refinement.hpp"
#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/frontend/keyframe_policy.hpp"
#include "cge/core/lens_distortion.hpp"
#include "cge/opencv/undistort.hpp"
#include "cge/slam/map_maintenance.hpp"

namespace cge {
namespace slam {

/// Dynamic handling of the ablation (docs/METHOD.md sections 1 and 8).
enum class DynamicMode : std::uint8_t {
  none,  ///< no dynamic handling, ORB-SLAM2-style keyframes (the baseline)
  Y,     ///< mask test only (labels dynamic_by_mask), ORB-SLAM2-style keyframes
  YM,    ///< masks + depth MAD (DepthMADFilter), ORB-SLAM2-style keyframes
  YMK,   ///< YM + PatchKeyframeSelector
};

inline const char* to_string(DynamicMode mode) {
  switch (mode) {
    case DynamicMode::none:
      return "none";
    case DynamicMode::Y:
      return "Y";
    case DynamicMode::YM:
      return "YM";
    case DynamicMode::YMK:
      return "YMK";
  }
  return "invalid";
}

/// "none", "Y", "YM" or "YMK"; throws std::invalid_argument naming the accepted values otherwise.
inline DynamicMode parse_dynamic_mode(const std::string& name) {
  if (name == "none") return DynamicMode::none;
  if (name == "Y") return DynamicMode::Y;
  if (name == "YM") return DynamicMode::YM;
  if (name == "YMK") return DynamicMode::YMK;
  throw std::invalid_argument("unknown mode '" + name + "' (expected none, Y, YM or YMK)");
}

inline bool uses_masks(DynamicMode mode) { return mode != DynamicMode::none; }
inline bool uses_mad(DynamicMode mode) { return mode == DynamicMode::YM || mode == DynamicMode::YMK; }
inline KeyframePolicyKind keyframe_policy_of(DynamicMode mode) {
  return mode == DynamicMode::YMK ? KeyframePolicyKind::patch : KeyframePolicyKind::orbslam2;
}

/// ORB extractor (the ORBextractor.* keys of an ORB-SLAM2 settings file).
struct OrbSettings {
  int features = 1000;              ///< nFeatures: keypoints per frame (ORB-SLAM2 TUM: 1000)
  double scale_factor = 1.2;        ///< scaleFactor: pyramid scale between levels, > 1
  int levels = 8;                   ///< nLevels: pyramid levels, >= 1
  int initial_fast_threshold = 20;  ///< iniThFAST: FAST threshold, intensity levels
  /// minThFAST: used for a second detection when the first finds fewer than `features` keypoints
  /// (cv::ORB has one threshold per call, not ORB-SLAM2's per-cell fallback).
  int min_fast_threshold = 7;
  int edge_threshold_px = 19;  ///< border without keypoints, pixels (ORB-SLAM2: 19)
  int patch_size_px = 31;      ///< ORB patch size, pixels (ORB-SLAM2: 31)
  /// Spreading keypoints over the image: cv::ORB keeps the corners with the best Harris scores, so
  /// a few textured regions take most features; ORB-SLAM2 spreads each pyramid level's corners
  /// over the image instead. With spread_oversampling s > 1, s x features candidates are detected
  /// and each level keeps its share (1 / s of its candidates) by taking the best of every cell in
  /// turn, then the second best, ... (cells of spread_cell_px at level 0, scaled with the level).
  /// 1 = off (cv::ORB's own choice), >= 1. Default 2: on the real fr1/rpy slice YMK's ATE fell from
  /// 3.9 to 2.8 cm and on rendered walking_xyz from 3.6 to 2.8 mm (docs/REAL_DATA.md).
  int spread_oversampling = 2;
  int spread_cell_px = 32;  ///< cell size at pyramid level 0, pixels, >= 1
};

/// What a Frame is made of.
struct FrameSettings {
  OrbSettings orb;
  /// Lens distortion of the colour camera (an ORB-SLAM2 file's Camera.k1 k2 p1 p2 k3). Keypoints
  /// are detected, masked and given depth in the image as it is; their undistorted positions
  /// (Frame::undistorted_px) are what geometry uses. Zero: an ideal pinhole camera (TUM fr3, synthetic).
  LensDistortion distortion;
  opencv::UndistortSettings undistort;  ///< the iteration that inverts the distortion
  double depth_units_per_metre = 5000;  ///< depth image scale (TUM: 5000 units = 1 m)
  double min_depth_m = 0.1;             ///< closer depths are treated as missing, metres
  /// Farther depths are treated as missing, metres (ORB-SLAM2 keeps points closer than 40 baselines,
  /// 40 * 0.08 m = 3.2 m on TUM; ours is wider because the synthetic depth is reliable further).
  double max_depth_m = 6.0;
  /// Close/far threshold, metres (ORB-SLAM2: ThDepth baselines, ThDepth * bf / fx; 40 * 40 / 535.4
  /// = 2.99 m for the synthetic camera.yaml and 3.09 m for TUM fr1). Close points always become map
  /// points of a new keyframe and drive the keyframe policy's close-point rule; far ones are
  /// added only to reach MappingSettings::min_new_points (depth noise grows with range).
  double close_depth_m = 40.0 * 40.0 / 535.4;
  DepthMADSettings mad;  ///< the filter of modes YM and YMK (r = 6 px and k = 1 the paper's, n = 100 ours)
};

/// Hypotheses of tracking's pose RANSAC. epnp: cv::solvePnPRansac, EPnP on five pixel matches,
/// then EPnP on all inliers. rigid: three matches with depth fitted in 3-D (cge/slam/geometry/
/// rigid_pose_ransac.hpp), then a 3-D refit on the inliers with depth.
enum class TrackingRansacSolver : std::uint8_t { epnp, rigid };

inline const char* tracking_ransac_solver_name(TrackingRansacSolver solver) {
  return solver == TrackingRansacSolver::rigid ? "rigid" : "epnp";
}

/// Tracking: prediction, matching to the local map, PnP, quality check, relocalisation.
struct TrackerSettings {
  int local_recent_keyframes = 5;      ///< local map: the last keyframes, count
  int local_covisible_keyframes = 10;  ///< local map: covisible keyframes of the reference keyframe, count
  double search_radius_px = 15;        ///< matching: window around a projected map point, pixels
  /// The wide window, as a multiple of search_radius_px, dimensionless: when tracking the local map
  /// at search_radius_px fails for any reason (fewer than min_matches matches, RANSAC or refinement
  /// short of min_inliers, a pose beyond max_jump_m), it is tried once more at this radius (a sudden
  /// change of motion); tracking against the last frame always matches within it.
  double wide_search_factor = 3;
  int max_hamming = 64;              ///< matching: largest descriptor distance accepted, bits of 256
  double ratio = 0.9;                ///< matching: best distance < ratio * second best (within the window)
  int min_matches = 20;              ///< fewer matches than this: the attempt fails (see wide_search_factor)
  /// How tracking's RANSAC makes its pose hypotheses from the matches (both score every match by
  /// its reprojection error at pnp_reprojection_px). Ours, default rigid: on the real fr1/rpy slice
  /// (nine start offsets) the tracking stage falls from 4.5-4.6 to 2.0-2.2 ms a frame, ATE none
  /// 26.2 -> 26.3 mm, YMK 25.7 -> 25.9 mm (within the offsets' spread); on the rendered walking
  /// presets mode none 14.9/11.7/19.7/13.4 -> 12.1/10.6/17.2/12.2 mm, YMK unchanged (docs/REAL_DATA.md).
  TrackingRansacSolver ransac_solver = TrackingRansacSolver::rigid;
  int pnp_iterations = 100;          ///< RANSAC iterations at most (samples)
  double pnp_reprojection_px = 3.0;  ///< RANSAC inlier threshold, pixels
  double pnp_confidence = 0.99;      ///< RANSAC confidence, in (0, 1)
  /// Inliers under this after refinement: the frame is lost (ORB-SLAM2 RGB-D: 30 in the local map).
  int min_inliers = 30;
  /// When the local map fails, track the frame against the previous frame's static keypoints with
  /// depth (odometry; needs min_matches matches and min_inliers inliers) before relocalising: the
  /// keyframes' map lags behind a fast turn (loop_dynamic at 181 frames lost 13 frames without it).
  bool track_last_frame = true;
  /// A tracked pose farther than this from the prediction is rejected as a wrong solution (the
  /// camera moves some centimetres per frame), metres.
  double max_jump_m = 0.3;
  /// Local-map tracking refines the pose from the prediction's matches directly and runs RANSAC
  /// only when that refinement fails (short of min_inliers or beyond max_jump_m), as ORB-SLAM2's
  /// motion-model tracking optimises from the prediction without RANSAC; false: RANSAC on every
  /// frame's matches first. Default false. Measured with EPnP hypotheses, true halved the tracking
  /// stage on the real fr1/rpy slice (5.1 -> 2.8 ms a frame; mode none 26.2 -> 23.8 mm, YMK 25.7 ->
  /// 25.6 mm over its nine start offsets; the rigid hypotheses now cost tens of microseconds, see
  /// bench_pose_ransac.cpp), but without dynamic filtering the refinement follows walking people that
  /// RANSAC's consensus leaves out: mode none on the rendered walking presets 13-20 -> 142-530 mm
  /// (docs/REAL_DATA.md). For static scenes or with masks (YMK unchanged within 0.1 mm there).
  bool ransac_only_on_failure = false;
  /// Motion-only refinement of the PnP pose (Ceres, Huber loss, chi2 outlier rounds; ORB-SLAM2's
  /// values). Each match's pixel sigma is scale_factor^octave of its keypoint.
  PoseRefinementSettings refinement;
  /// Depth term of the refinement: each match whose keypoint has depth z also constrains the pose by
  /// that depth with sigma_z = refinement_depth_sigma_per_m * z^2 (Kinect-like growth), 1/m; 0 = pixels
  /// only. Pixels alone leave the rotation about the scene's centre (with the matching sideways
  /// translation) weakly determined: that was most of the frame-to-frame jitter on the walking presets.
  double refinement_depth_sigma_per_m = 0.003;
  /// The first frame initialises the map only with at least this many static keypoints with
  /// depth (ORB-SLAM2 RGB-D: 500); with fewer it is reported lost and the next frame tries.
  int min_initial_points = 100;
  int relocalisation_keyframes = 10;  ///< relocalisation tries the last keyframes, count
  /// Relocalisation first tries at most this many keyframes of the candidate source (the System's
  /// bag-of-words query over all keyframes, best score first), count; ORB-SLAM2 also searches the
  /// whole map, so a camera lost away from the last keyframes can come back.
  int relocalisation_candidates = 10;
  int min_relocalisation_inliers = 50;  ///< PnP inliers to accept a relocalisation
};

/// Map points created from depth.
struct MappingSettings {
  /// New map points only from keypoints closer than this, metres (a hard cap above the close/far rule).
  double max_new_point_depth_m = 5.0;
  /// ORB-SLAM2's rule for a new keyframe's points (Tracking::CreateNewKeyFrame): from its untracked
  /// static keypoints with depth, nearest first, every close one (FrameSettings::close_depth_m) and
  /// far ones only until the keyframe observes min_new_points. Off: every one closer than
  /// max_new_point_depth_m. Off by default: without ORB-SLAM2's monocular triangulation of far
  /// points the map then lacks them, and the error grew on real and rendered frames (docs/REAL_DATA.md).
  bool only_close_new_points = false;
  int min_new_points = 100;  ///< with only_close_new_points (ORB-SLAM2: 100), count >= 0
  /// The ORB-SLAM2 baseline compares a frame's tracked points with the reference keyframe's map
  /// points observed at least this many times, >= 1 (2 at most while the map has at most 2
  /// keyframes; ORB-SLAM2 Tracking::NeedNewKeyFrame: nMinObs = 3).
  int reference_min_observations = 3;
  /// Observations with depth count twice there, as ORB-SLAM2 counts stereo/RGB-D ones
  /// (weighted_observations, cge/slam/map_maintenance.hpp): nMinObs 3 means two keyframes with depth.
};

/// Local bundle adjustment after each keyframe insertion (ORB-SLAM2's local mapping): the new
/// keyframe and its most covisible keyframes (the window) are optimised together with the map points
/// they observe (points seen by at least two keyframes); every other keyframe observing those points
/// contributes its observations with its pose fixed, and keyframe 0 is always fixed (the gauge).
/// Pixel + depth observations, Huber then chi2 outlier removal (BundleAdjustmentSettings). Map points
/// made from one keyframe's noisy depth are otherwise never refined.
struct LocalMappingSettings {
  // Map maintenance after each keyframe, in ORB-SLAM2's order (LocalMapping::Run): recent points
  // culled, new points triangulated, duplicates fused, local BA, redundant keyframes culled.
  bool cull_map_points = true;      ///< cull_recent_map_points (cge/slam/map_maintenance.hpp)
  /// triangulate_new_points for keypoints without usable depth. Off by default: on the real fr1/rpy
  /// slice it gave no gain in mode YMK (2.68 vs 2.74 cm) and, with keyframe culling, sent mode none
  /// from 2.5 to 12 cm (docs/REAL_DATA.md); RGB-D keypoints mostly have depth.
  bool triangulate_points = false;
  bool fuse_map_points = true;      ///< fuse_map_points among covisible keyframes
  bool cull_keyframes = true;       ///< cull_redundant_keyframes (its close_depth_m follows FrameSettings)
  MapMaintenanceSettings maintenance;
  bool bundle_adjustment = true;  ///< false: keyframes and map points stay as tracking made them
  /// Window: the new keyframe and at most this many most covisible keyframes, count >= 0 (ours;
  /// ORB-SLAM2 takes every covisible keyframe). 20 against 10: on the real fr1/rpy slice the mean
  /// ATE over five keyframe settings fell from 31.8 to 31.0 mm (YMK) and 25.0 to 23.7 mm (none),
  /// the rendered presets moved by at most 0.1 mm, the local-mapping time rose by half
  /// (docs/REAL_DATA.md, item 12).
  int covisible_keyframes = 20;
  /// Fixed observers: of the keyframes outside the window that see its points, only this many
  /// with most observations of them enter (held fixed); observations from the others are left out. Without a cap, a policy that makes nearly every frame a keyframe (ORB-SLAM2-style, no
  /// keyframe culling) puts hundreds of fixed poses into every window (seconds per keyframe).
  /// Count >= 0 (0: the window alone, which then needs keyframe 0 in it for the gauge).
  int fixed_keyframes = 10;
  /// Depth standard deviation: sigma_z = depth_sigma_per_m * z^2 (Kinect-like growth), 1/m, > 0.
  double depth_sigma_per_m = 0.003;
  /// Local-BA rounds solved per camera frame, >= 1, each before the frame is tracked; once every
  /// round is solved, the keyframe's redundant keyframes are culled and its loop closed. A
  /// keyframe's frame then no longer carries the whole BA (ORB-SLAM2 runs it in a thread of its
  /// own). >= bundle.rounds solves the whole BA in one frame.
  int ba_rounds_per_frame = 1;
  /// Where the rounds start. true: the keyframe's own frame does the map maintenance and collects
  /// the window, and the first round is solved by the next frame before it is tracked, so that
  /// frame is tracked against the window as the first round leaves it (ORB-SLAM2's tracking goes on
  /// while its mapping thread optimises). false: the keyframe's frame solves the first round itself
  /// and every frame is tracked in the map the whole BA leaves. Ours, default true: on the real
  /// fr1/rpy slice (nine start offsets) the 95th percentile of the time per frame falls from
  /// 2.6-3.1x to 1.8-2.1x the median, the median rises 1-4 ms, ATE YMK 25.7 -> 25.7 mm, none
  /// 25.1 -> 26.2 mm (within the offsets' spread; docs/REAL_DATA.md).
  bool ba_from_next_frame = true;
  /// When > 0: Levenberg-Marquardt iterations of the pending local BA solved per camera frame,
  /// over rounds, instead of whole rounds (ba_rounds_per_frame is then unused). Each slice restarts
  /// the solver from the current estimate and writes it into the map, so the frames in between are
  /// tracked against a partly optimised window, as ORB-SLAM2's tracking runs while its local BA
  /// iterates. Changes the trajectory. 0: whole rounds. Count >= 0; default 0 (docs/REAL_DATA.md).
  int ba_iterations_per_frame = 0;
  /// Rounds, loss and iterations: a Huber round and a plain round on the chi2 inliers, as ORB-SLAM2.
  BundleAdjustmentSettings bundle = [] {
    BundleAdjustmentSettings b;
    // Per round. ORB-SLAM2 Optimizer.cc LocalBundleAdjustment: optimize(5), then optimize(10)
    // without the outliers; ours caps both at 5 (the plain round stops after 2-3 on the real
    // fr1/rpy slice). 10 gave a 95th percentile a quarter higher, ATE no better (docs/REAL_DATA.md).
    b.solver.max_iterations = 5;
    // A relative cost change of 1e-6 is converged enough for a window the next keyframe adjusts
    // again (1e-10: 8 iterations instead of 3 on a 13 000-observation window, same cost to 1e-8).
    b.solver.function_tolerance = 1e-6;
    b.sparse_schur = false;        // at most 1 + covisible + fixed keyframes: dense Schur
    // cge's own Schur LM: on the real fr1/rpy slice the local-mapping time summed over the run is
    // 2.5-4x lower than with Ceres and the 95th percentile of the frame time falls from 3.4-3.7x
    // to 1.9-2.2x the median, ATE unchanged within the slice's noise (docs/REAL_DATA.md).
    b.backend = BundleAdjustmentBackend::schur_lm;
    return b;
  }();
};

/// Correction of an accepted loop (docs/METHOD.md section 7, step 5; cge/slam/loop_correction.hpp):
/// a pose graph over all keyframes (sequential, covisibility and every accepted loop edge), map
/// points moved with their first keyframe, then global bundle adjustment.
struct LoopCorrectionSettings {
  bool enabled = true;  ///< false: loops are only detected and logged (loops.csv), never corrected
  /// After a correction, accepted loops within this many keyframes only add their edge to the
  /// graph (one revisit is accepted at many consecutive keyframes), keyframes, >= 0. 10 as the
  /// gap ORB-SLAM2 keeps after a loop (LoopClosing.cc, DetectLoop: there it skips detection,
  /// here only the correction).
  int min_keyframes_between = 10;
  /// Covisibility edges join keyframes sharing at least this many map points, points, >= 1
  /// (ORB-SLAM2 Optimizer.cc, OptimizeEssentialGraph: minFeat 100).
  int covisibility_min_shared_points = 100;
  /// Pose-graph edge information, the same on every edge (ORB-SLAM2's essential graph uses one
  /// information matrix for all edges too); ours: without a robust loss only the ratio of the two
  /// shapes the optimum.
  double rotation_weight = 1e4;     ///< 1/rad^2, > 0
  double translation_weight = 1e4;  ///< 1/m^2, > 0
  bool bundle_adjustment = true;    ///< global BA after the pose graph (ORB-SLAM2 runs one after a loop)
  /// Depth standard deviation in BA: sigma_z = depth_sigma_per_m * z^2 (Kinect-like growth), 1/m,
  /// > 0; ours, as TrackerSettings::refinement_depth_sigma_per_m (an ORB-SLAM2 settings file sets
  /// it, cge/slam/settings_from_orbslam2.hpp).
  double depth_sigma_per_m = 0.003;
  PoseGraphSettings pose_graph;
  /// Global BA on cge's own Schur LM (dense reduced system, Ceres' sparse Schur beyond
  /// schur_lm_max_free_poses): on the main job's two corrections 25 / 307 ms against 157 / 1643 ms
  /// with Ceres, the same loops and ATE to 1e-8 m (docs/OPTIMISATION.md).
  BundleAdjustmentSettings bundle = [] {
    BundleAdjustmentSettings b;
    b.backend = BundleAdjustmentBackend::schur_lm;
    return b;
  }();

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    const auto fail = [](const std::string& what) {
      throw std::invalid_argument("LoopCorrectionSettings: " + what);
    };
    if (min_keyframes_between < 0) fail("min_keyframes_between must not be negative");
    if (covisibility_min_shared_points < 1) fail("covisibility_min_shared_points must be at least 1");
    if (!(rotation_weight > 0 && translation_weight > 0)) fail("rotation_weight and translation_weight must be > 0");
    if (!(depth_sigma_per_m > 0)) fail("depth_sigma_per_m must be > 0");
    pose_graph.validate();
    bundle.validate();
  }
};

/// Everything the System needs. Validate with validate(); throws std::invalid_argument naming a field.
struct SystemSettings {
  DynamicMode mode = DynamicMode::YMK;
  FrameSettings frame;
  TrackerSettings tracker;
  MappingSettings mapping;
  LocalMappingSettings local_mapping;
  LoopCorrectionSettings loop_correction;
  PatchKeyframeSettings<double> patch_keyframes;        ///< mode YMK
  /// Modes none, Y, YM. min_frame_gap 5 stands in for the time ORB-SLAM2's local-mapping thread is
  /// busy after a keyframe (c1b needs it idle; about 0.17 s at 30 fps): with 0 the serial pipeline
  /// kept 151 keyframes on the real fr1/rpy slice where ORB-SLAM2 keeps 39-43 (docs/REAL_DATA.md).
  OrbSlam2KeyframeSettings<double> orbslam2_keyframes = [] {
    OrbSlam2KeyframeSettings<double> k;
    k.min_frame_gap = 5;
    return k;
  }();
  std::uint64_t seed = 0;             ///< the MAD filter's samples: frame i uses a seed derived from (seed, i)
  bool keep_keyframe_images = false;  ///< keep bgr/depth in keyframes (for the dense maps, docs/MAPS.md)

  void validate() const {
    const auto fail = [](const std::string& what) { throw std::invalid_argument("SystemSettings: " + what); };
    const OrbSettings& o = frame.orb;
    if (o.features < 1) fail("frame.orb.features must be at least 1");
    if (!(o.scale_factor > 1)) fail("frame.orb.scale_factor must be > 1");
    if (o.levels < 1) fail("frame.orb.levels must be at least 1");
    if (o.initial_fast_threshold < 1 || o.min_fast_threshold < 1) fail("frame.orb FAST thresholds must be >= 1");
    if (o.spread_oversampling < 1) fail("frame.orb.spread_oversampling must be at least 1");
    if (o.spread_cell_px < 1) fail("frame.orb.spread_cell_px must be at least 1");
    if (!(frame.depth_units_per_metre > 0)) fail("frame.depth_units_per_metre must be > 0");
    if (!(frame.min_depth_m >= 0 && frame.max_depth_m > frame.min_depth_m)) fail("frame depth range is empty");
    if (!frame.distortion.is_finite()) fail("frame.distortion coefficients must be finite");
    frame.undistort.validate();
    frame.mad.validate();
    const TrackerSettings& t = tracker;
    if (t.local_recent_keyframes < 1) fail("tracker.local_recent_keyframes must be at least 1");
    if (t.local_covisible_keyframes < 0) fail("tracker.local_covisible_keyframes must not be negative");
    if (!(t.search_radius_px > 0)) fail("tracker.search_radius_px must be > 0");
    if (!(t.wide_search_factor >= 1)) fail("tracker.wide_search_factor must be >= 1");
    if (t.max_hamming < 0 || t.max_hamming > 256) fail("tracker.max_hamming must be in 0 .. 256");
    if (!(t.ratio > 0 && t.ratio <= 1)) fail("tracker.ratio must be in (0, 1]");
    if (t.min_matches < 4 || t.min_inliers < 4) fail("tracker.min_matches and min_inliers must be at least 4");
    if (t.pnp_iterations < 1) fail("tracker.pnp_iterations must be at least 1");
    if (!(t.pnp_reprojection_px > 0)) fail("tracker.pnp_reprojection_px must be > 0");
    if (!(t.pnp_confidence > 0 && t.pnp_confidence < 1)) fail("tracker.pnp_confidence must be in (0, 1)");
    if (!(t.max_jump_m > 0)) fail("tracker.max_jump_m must be > 0");
    t.refinement.validate();
    if (!(std::isfinite(t.refinement_depth_sigma_per_m) && t.refinement_depth_sigma_per_m >= 0))
      fail("tracker.refinement_depth_sigma_per_m must be finite and not negative");
    if (t.min_initial_points < 4) fail("tracker.min_initial_points must be at least 4");
    if (t.relocalisation_keyframes < 0) fail("tracker.relocalisation_keyframes must not be negative");
    if (t.relocalisation_candidates < 0) fail("tracker.relocalisation_candidates must not be negative");
    if (t.min_relocalisation_inliers < 4) fail("tracker.min_relocalisation_inliers must be at least 4");
    if (!(mapping.max_new_point_depth_m > 0)) fail("mapping.max_new_point_depth_m must be > 0");
    if (mapping.reference_min_observations < 1) fail("mapping.reference_min_observations must be at least 1");
    if (mapping.min_new_points < 0) fail("mapping.min_new_points must not be negative");
    if (!(frame.close_depth_m > 0)) fail("frame.close_depth_m must be > 0");
    if (local_mapping.covisible_keyframes < 0) fail("local_mapping.covisible_keyframes must not be negative");
    if (local_mapping.fixed_keyframes < 0) fail("local_mapping.fixed_keyframes must not be negative");
    if (local_mapping.ba_rounds_per_frame < 1) fail("local_mapping.ba_rounds_per_frame must be at least 1");
    if (local_mapping.ba_iterations_per_frame < 0)
      fail("local_mapping.ba_iterations_per_frame must not be negative");
    if (!(local_mapping.depth_sigma_per_m > 0)) fail("local_mapping.depth_sigma_per_m must be > 0");
    local_mapping.bundle.validate();
    local_mapping.maintenance.validate();
    loop_correction.validate();
    patch_keyframes.validate();
    orbslam2_keyframes.validate();
  }
};

}  // namespace slam
}  // namespace cge
