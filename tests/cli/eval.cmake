# Command-line tests of cge_eval (included by CMakeLists.txt when the tool is built). The fixtures
# under eval/ are hand-made; the expected values are worked out in docs/EVALUATION.md and
# tests/test_metrics_*.cpp (same constructions), not taken from the tool.

# ATE, six points on the axes, each +-p pair displaced by the same d_k (d1 + d2 + d3 = 0): the
# alignment cannot reduce the errors |d_k| = 0.03, 0.04, sqrt(0.0017). The estimate's first pose
# (0.5 s) has no ground truth; the others are 0.01 s late (within --max-difference 0.02).
set(ev_ate_values
  "compared_pose_pairs 6" "ate_rmse_m 0\\.03741657386773[0-9]*" "ate_mean_m 0\\.03707701875205[0-9]*"
  "ate_median_m 0\\.0(4|399999999999[0-9]*)" "ate_std_m 0\\.0050293817174[0-9]*" "ate_min_m 0\\.0(3|29999999999[0-9]*)"
  "ate_max_m 0\\.04123105625617[0-9]*")
cge_cli_test(eval_ate PROGRAM cge_eval ARGS ate eval/gt.txt eval/est.txt
  STDOUT "groundtruth_poses 6" "estimate_poses 7" ${ev_ate_values})
# The same estimate in another world frame (rotated and shifted, comma-separated): same errors.
cge_cli_test(eval_ate_rotated PROGRAM cge_eval ARGS ate eval/gt.txt eval/est_rotated.txt STDOUT ${ev_ate_values})
# A maximum difference below the 0.01 s lag associates nothing.
cge_cli_test(eval_ate_max_difference PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/est.txt --max-difference 0.005
  STDERR "ATE: no timestamp")
cge_cli_test(eval_ate_offset PROGRAM cge_eval ARGS ate eval/gt.txt eval/est.txt --max-difference 0.005 --offset -0.01
  STDOUT "compared_pose_pairs 6" "ate_rmse_m 0\\.03741657386773[0-9]*")
cge_cli_test(eval_ate_json PROGRAM cge_eval ARGS ate eval/gt.txt eval/est.txt --json
  STDOUT [[ *"tool": "cge_eval",]] [[ *"command": "ate",]] [[ *"groundtruth": "eval/gt.txt",]]
         [[ *"compared_pose_pairs": 6,]] [[ *"ate_rmse_m": 0\.03741657386773[0-9]*,]] [[ *"ate_max_m": 0\.0412310562561[0-9]*]])
cge_cli_test(eval_ate_no_overlap PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/far.txt STDERR "ATE: no timestamp")

# RPE: the estimate moves at 1.1 m/s where the ground truth moves at 1 m/s (10 Hz, 101 poses):
# 0.1 m error per second; pairs i = 0 .. 89 (the tool drops pairs ending on the last pose).
cge_cli_test(eval_rpe PROGRAM cge_eval ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt
  STDOUT "compared_pose_pairs 90" "rpe_trans_rmse_m 0\\.(1|0999999999[0-9]*|1000000000[0-9]*)"
         "rpe_trans_max_m 0\\.(1|0999999999[0-9]*|1000000000[0-9]*)" "rpe_rot_rmse_deg 0" "rpe_rot_mean_deg 0")
cge_cli_test(eval_rpe_frames PROGRAM cge_eval ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 10 --delta-unit frames
  STDOUT "compared_pose_pairs 90" "rpe_trans_mean_m 0\\.(1|0999999999[0-9]*|1000000000[0-9]*)")
cge_cli_test(eval_rpe_one_frame PROGRAM cge_eval ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 1 --delta-unit frames
  STDOUT "compared_pose_pairs 99" "rpe_trans_mean_m 0\\.(01|0099999999[0-9]*|0100000000[0-9]*)")
cge_cli_test(eval_rpe_json PROGRAM cge_eval ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --json
  STDOUT [[ *"command": "rpe",]] [[ *"delta_unit": "s"]] [[ *"compared_pose_pairs": 90,]] [[ *"rpe_rot_max_deg": 0\.0]])
cge_cli_test(eval_rpe_bad_delta PROGRAM cge_eval EXIT 2 ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 0
  STDERR "--delta must be a finite positive number")
cge_cli_test(eval_rpe_fractional_frames PROGRAM cge_eval EXIT 2
  ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 1.5 --delta-unit frames STDERR "whole number")
cge_cli_test(eval_rpe_bad_unit PROGRAM cge_eval EXIT 2 ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta-unit m
  STDERR "--delta-unit")
cge_cli_test(eval_rpe_too_short PROGRAM cge_eval EXIT 2 ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 20
  STDERR "fewer than two pose pairs")

# Loops, the hand-worked log of tests/test_metrics_loops.cpp: 3 detections, 1 correct; loop
# keyframes 10, 11, 12, 17, 18 (1 recognised) in two events ({10, 11, 12}, {17, 18}).
cge_cli_test(eval_loops PROGRAM cge_eval ARGS loops eval/loops.txt eval/loops.csv
  STDOUT "ground_truth_pairs 7" "queried_keyframes 8" "detections 3" "correct_detections 1"
         "precision 0\\.333333333333333" "loop_queries 5" "detected_loop_queries 1" "query_recall 0\\.2"
         "loop_events 2" "detected_loop_events 1" "event_recall 0\\.5")
# The same log with misses by reason; extended with keyframes at 1, 2 and 5 s and the connected
# keyframes: 11 and 18 s have every keyframe partner connected, 10, 12 and 17 s are open.
cge_cli_test(eval_loops_misses PROGRAM cge_eval ARGS loops eval/loops.txt eval/loops.csv
  STDOUT "missed_loop_queries 4" "missed_no_candidates 1" "missed_low_score 1" "missed_continuity 0"
         "missed_too_few_matches 1" "missed_pose_not_robust 0" "missed_wrong_match 1"
  STDERR "no connected_keyframes column")
cge_cli_test(eval_loops_open PROGRAM cge_eval ARGS loops eval/loops.txt eval/loops_extended.csv
  STDOUT "query_recall 0\\.2" "event_recall 0\\.5" "loop_queries_without_keyframe_partner 0"
         "connected_loop_queries 2" "open_loop_queries 3" "detected_open_loop_queries 1"
         "open_query_recall 0\\.333333333333333" "open_missed_loop_queries 2" "open_missed_low_score 1"
         "open_missed_too_few_matches 1" "open_missed_wrong_match 0")
cge_cli_test(eval_loops_nan PROGRAM cge_eval ARGS loops eval/loops.txt eval/loops_none_accepted.csv
  STDOUT "detections 0" "precision nan" "query_recall 0" STDERR "precision is undefined")
cge_cli_test(eval_loops_json_null PROGRAM cge_eval ARGS loops eval/loops.txt eval/loops_none_accepted.csv --json
  STDOUT [[ *"precision": null,]] [[ *"event_recall": 0\.0,]])
cge_cli_test(eval_loops_tolerance PROGRAM cge_eval EXIT 2 ARGS loops eval/loops.txt eval/loops.csv --tolerance -1
  STDERR "--tolerance")

# Malformed input: the file and line, exit code 2, nothing on stdout.
cge_cli_test(eval_bad_fields PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/bad_fields.txt
  STDERR "eval/bad_fields\\.txt:3: expected 8 fields \\(timestamp tx ty tz qx qy qz qw\\), found 7")
cge_cli_test(eval_bad_number PROGRAM cge_eval EXIT 2 ARGS ate eval/bad_number.txt eval/gt.txt
  STDERR "eval/bad_number\\.txt:3: tz '0\\.5O' is not a number")
cge_cli_test(eval_bad_commas PROGRAM cge_eval EXIT 2 ARGS rpe eval/gt.txt eval/bad_commas.txt
  STDERR "eval/bad_commas\\.txt:2: expected 8 fields.*found 9")
cge_cli_test(eval_bad_quaternion PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/bad_quaternion.txt
  STDERR "eval/bad_quaternion\\.txt:2: quaternion norm 1\\.249[0-9]* is not close to 1")
cge_cli_test(eval_bad_order PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/bad_order.txt
  STDERR "eval/bad_order\\.txt:3: timestamp 2\\.0 does not come after the one on line 2")
# A repeated timestamp (as in the official fr3/walking_static and fr2/desk ground truth): the TUM
# tools keep the later line, and so does the default, with a warning naming the file and line.
cge_cli_test(eval_duplicate PROGRAM cge_eval ARGS ate eval/duplicate.txt eval/est.txt
  STDOUT "groundtruth_poses 6" "compared_pose_pairs 6" STDERR "^cge_eval: warning: eval/duplicate\\.txt:2: pose replaced")
cge_cli_test(eval_duplicate_strict PROGRAM cge_eval EXIT 2 ARGS ate eval/duplicate.txt eval/est.txt --duplicate-stamps error
  STDERR "eval/duplicate\\.txt:3: timestamp 2\\.0000 repeats the one on line 2" "--duplicate-stamps error")
cge_cli_test(eval_duplicate_last PROGRAM cge_eval ARGS ate eval/duplicate.txt eval/est.txt --duplicate-stamps last
  STDOUT "groundtruth_poses 6" "compared_pose_pairs 6" STDERR "duplicate\\.txt:2: pose replaced")
# No silent wrong numbers: two pairs fit a rigid alignment exactly (ATE 0 whatever the estimate), a
# delta far beyond the trajectory paired every pose with the first, a duplicated loops.csv row
# counted twice.
cge_cli_test(eval_ate_two_pairs PROGRAM cge_eval EXIT 2 ARGS ate eval/gt_two_poses.txt eval/est.txt
  STDERR "ATE: only 2 pose pair\\(s\\) associate; at least 3")
cge_cli_test(eval_rpe_huge_delta PROGRAM cge_eval EXIT 2 ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 1e16
  STDERR "delta 1e\\+16 s is not shorter than the estimate's span of 10 s")
cge_cli_test(eval_rpe_huge_delta_frames PROGRAM cge_eval EXIT 2
  ARGS rpe eval/rpe_gt.txt eval/rpe_est.txt --delta 1e16 --delta-unit frames STDERR "span of 100 frames")
cge_cli_test(eval_loops_duplicate_row PROGRAM cge_eval EXIT 2 ARGS loops eval/loops.txt eval/loops_duplicate_row.csv
  STDERR "eval/loops_duplicate_row\\.csv:10: query_keyframe 7 repeats the row on line 3")
cge_cli_test(eval_empty PROGRAM cge_eval EXIT 2 ARGS ate empty.txt eval/est.txt STDERR "empty\\.txt: the file contains no poses")
cge_cli_test(eval_missing PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/no_such_file.txt
  STDERR "cannot open 'eval/no_such_file\\.txt'")
cge_cli_test(eval_folder PROGRAM cge_eval EXIT 2 ARGS ate eval eval/gt.txt STDERR "'eval': it is a directory")
cge_cli_test(eval_bad_loops_txt PROGRAM cge_eval EXIT 2 ARGS loops eval/bad_loops.txt eval/loops.csv
  STDERR "eval/bad_loops\\.txt:3: match_index 11 is not smaller than query_index 1")
cge_cli_test(eval_bad_loops_csv PROGRAM cge_eval EXIT 2 ARGS loops eval/loops.txt eval/bad_loops.csv
  STDERR "eval/bad_loops\\.csv:3: accepted 'yes' is not 0 or 1")
cge_cli_test(eval_bad_header PROGRAM cge_eval EXIT 2 ARGS loops eval/loops.txt eval/bad_header.csv
  STDERR "eval/bad_header\\.csv:1: expected the header")
cge_cli_test(eval_loops_csv_as_trajectory PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/loops.csv
  STDERR "eval/loops\\.csv:1: expected 8 fields")

# Usage.
cge_cli_test(eval_no_command PROGRAM cge_eval EXIT 2 STDERR "subcommand")
cge_cli_test(eval_missing_est PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt STDERR "EST")
cge_cli_test(eval_bad_max_difference PROGRAM cge_eval EXIT 2 ARGS ate eval/gt.txt eval/est.txt --max-difference -1
  STDERR "--max-difference must be a finite positive number")
cge_cli_test(eval_help PROGRAM cge_eval ARGS --help STDOUT ".*ate.*" ".*rpe.*" ".*loops.*")
cge_cli_test(eval_rpe_help PROGRAM cge_eval ARGS rpe --help STDOUT ".*--delta-unit.*" ".*--duplicate-stamps.*")
string(REPLACE "." "\\." ev_version_regex "${PROJECT_VERSION}")
cge_cli_test(eval_version PROGRAM cge_eval ARGS --version STDOUT "cge_eval ${ev_version_regex}")

# The real TUM files, when the shared data is there. The figures themselves are checked against
# independent oracles in tests/test_metrics_trajectory.cpp; here only that the tool reads the files
# and prints plausible values (RGB-D SLAM on fr1_xyz is good to 1 .. 5 cm, 786 of 788 poses pair).
set(ev_tum "${PROJECT_SOURCE_DIR}/../shared/data/tum_trajectories")
if(EXISTS "${ev_tum}/freiburg1_xyz-rgbdslam.txt" AND EXISTS "${ev_tum}/freiburg1_xyz-groundtruth.txt")
  cge_cli_test(eval_tum_fr1_xyz_ate PROGRAM cge_eval
    ARGS ate ${ev_tum}/freiburg1_xyz-groundtruth.txt ${ev_tum}/freiburg1_xyz-rgbdslam.txt
    STDOUT "estimate_poses 788" "compared_pose_pairs 78[0-8]" "ate_rmse_m 0\\.0[1-4][0-9]*")
  cge_cli_test(eval_tum_fr1_xyz_rpe PROGRAM cge_eval
    ARGS rpe ${ev_tum}/freiburg1_xyz-groundtruth.txt ${ev_tum}/freiburg1_xyz-rgbdslam.txt
    STDOUT "compared_pose_pairs 7[0-9][0-9]" "rpe_trans_rmse_m 0\\.0[0-9]+" "rpe_rot_rmse_deg [0-2]\\.[0-9]+")
else()
  message(STATUS "cge: ${ev_tum} is absent, the cge_eval tests on real TUM files are skipped")
endif()

# map (only when cge_eval has the pipeline): eval/map3.ot is a ColorOcTree of resolution 0.1 m written
# by OctoMap 1.9.7 with three occupied voxels: chair orange (255,140,0) at indices (0,0,0) and (1,1,0),
# grey at (1,0,0). One 26-connected chair component whose box (0..1, 0..1, 0) holds all three voxels:
# S_int = 2/3 for its single entity, fluctuation 0; with the default --min-entity-voxels 3 no entity.
# eval/map3.bt is an OcTree (.bt), which the map subcommand refuses.
if(TARGET cge_pipeline)
  cge_cli_test(eval_map PROGRAM cge_eval ARGS map eval/map3.ot --min-entity-voxels 1
    STDOUT "resolution_m 0\\.1" "occupied_voxels 3" "entities 1" "integrity 0\\.66666666666666[67]" "fluctuation 0")
  cge_cli_test(eval_map_small_components PROGRAM cge_eval ARGS map eval/map3.ot
    STDOUT "occupied_voxels 3" "entities 0" "integrity 0")
  cge_cli_test(eval_map_bt PROGRAM cge_eval EXIT 2 ARGS map eval/map3.bt STDERR "is not an OctoMap \\.ot file")
  cge_cli_test(eval_map_missing PROGRAM cge_eval EXIT 2 ARGS map eval/no_such_map.ot STDERR "is not a readable file")
  # A truncated octree (the header and 100 of its 152 node bytes) is refused, not read as another
  # map; a folder is called a folder; OctoMap's own chatter stays off standard error.
  cge_cli_test(eval_map_truncated PROGRAM cge_eval EXIT 2 ARGS map eval/map3_truncated.ot
    STDERR "^cge_eval: error: read_color_octree: eval/map3_truncated\\.ot is truncated or corrupt: the data ends after 12 of 19 nodes")
  cge_cli_test(eval_map_quiet PROGRAM cge_eval ARGS map eval/map3.ot STDOUT "occupied_voxels 3" STDERR "^$")
  cge_cli_test(eval_map_folder PROGRAM cge_eval EXIT 2 ARGS map eval STDERR "^cge_eval: error: read_color_octree: eval is a directory")
  cge_cli_test(eval_map_keyframes_without_sequence PROGRAM cge_eval EXIT 2 ARGS map eval/map3.ot --keyframes eval/gt.txt
    STDERR "--keyframes needs --sequence")
  cge_cli_test(eval_map_trajectory_without_sequence PROGRAM cge_eval EXIT 2 ARGS map eval/map3.ot --trajectory eval/gt.txt
    STDERR "--trajectory needs --sequence")
endif()

# Threshold sweep and score gate of loops (eval/loops_curve.csv: the log of
# tests/test_metrics_outputs.cpp, hand-worked there), and the files --curve and --aligned-out write.
cge_cli_test(eval_loops_min_score PROGRAM cge_eval ARGS loops eval/loops.txt eval/loops_curve.csv --min-score 0.7
  STDOUT "detections 3" "correct_detections 2" "precision 0\\.666666666666667" "query_recall 0\\.4" "event_recall 1")
cge_cli_test(eval_loops_min_score_bow PROGRAM cge_eval
  ARGS loops eval/loops.txt eval/loops_curve.csv --score bow_score --min-score 0.4
  STDOUT "detections 4" "correct_detections 2" "precision 0\\.5" "query_recall 0\\.4" "event_recall 0\\.5")
cge_cli_test(eval_loops_bad_score PROGRAM cge_eval EXIT 2 ARGS loops eval/loops.txt eval/loops_curve.csv --score S_sum
  STDERR "--score")
cge_cli_test(eval_loops_bad_min_score PROGRAM cge_eval EXIT 2
  ARGS loops eval/loops.txt eval/loops_curve.csv --min-score nan STDERR "--min-score")
add_test(NAME cli.eval_curve_and_aligned_out
         COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:cge_eval> -DWORK=${CMAKE_CURRENT_BINARY_DIR}/eval_outputs
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/run_eval_outputs.cmake
         WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
