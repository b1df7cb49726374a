# Command-line test of cge_slam's leak count and loop settings in its outputs:
#   cmake -DEXE=<cge_slam> [-DSIM=<cge_sim>] -DWORK=<a folder of this test's own> -P run_slam_leak.cmake
# 1. rendered walking_xyz (no --dataset), mode none: every frame has ground truth, nothing is
#    filtered, so moving_kept == moving_keypoints in frames.csv and summary.json; loop_settings
#    holds the defaults (combined, min_cge_score 0.5, normalised).
#    mapping_settings holds the tracking and local-BA defaults.
# 1b. --tracking-depth-sigma 0 and --local-ba off are recorded and change the trajectory.
# 1c. --keyframe-interval is recorded and changes mode YMK's keyframes; 0 is refused (exit 2);
#     --semantic-change-frames is recorded; 0 is refused.
# 2. --loop-scoring bow_only --loop-min-score 0.1 --cge-scaling raw are recorded in loop_settings.
# 3. (with cge_sim) the same sequence written to a folder: the masks/ folder gives the same
#    moving_keypoints per frame as the in-process renderer's labels; without masks/instances.csv
#    (as real TUM data) no frame has ground truth and the rate is null.
cmake_minimum_required(VERSION 3.19)

foreach(var EXE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_slam_leak.cmake: ${var} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
set(frames 6)
set(common --frames ${frames} --seed 3)

function(run_tool expected_rc)
  execute_process(COMMAND ${ARGN} INPUT_FILE "${CMAKE_CURRENT_LIST_DIR}/empty.txt"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
  if(NOT "${rc}" STREQUAL "${expected_rc}")
    message(FATAL_ERROR "${ARGN}: exit code ${rc}, expected ${expected_rc}\n--- stdout ---\n${out}--- stderr ---\n${err}")
  endif()
endfunction()

# `expected` is a regex matched against the whole value (CMake prints JSON numbers with 17 digits).
function(expect_json file expected)
  file(READ "${file}" json)
  string(JSON value GET "${json}" ${ARGN})
  if(NOT "${value}" MATCHES "^${expected}$")
    message(FATAL_ERROR "${file}: ${ARGN} is '${value}', expected '${expected}'")
  endif()
endfunction()

# The moving_keypoints and moving_kept columns of frames.csv (the last two) as "a/b;a/b;...".
function(moving_columns file result)
  file(STRINGS "${file}" lines)
  list(POP_FRONT lines header)
  if(NOT header MATCHES ",moving_keypoints,moving_kept$")
    message(FATAL_ERROR "${file}: the header does not end with moving_keypoints,moving_kept: ${header}")
  endif()
  set(pairs)
  foreach(line IN LISTS lines)
    if(NOT line MATCHES ",(-?[0-9]+),(-?[0-9]+)$")
      message(FATAL_ERROR "${file}: no moving counts at the end of '${line}'")
    endif()
    list(APPEND pairs "${CMAKE_MATCH_1}/${CMAKE_MATCH_2}")
  endforeach()
  set(${result} "${pairs}" PARENT_SCOPE)
endfunction()

# 1.
run_tool(0 "${EXE}" ${common} --mode none --out "${WORK}/rendered")
set(summary "${WORK}/rendered/summary.json")
expect_json("${summary}" ${frames} dynamic_leak frames_with_ground_truth)
file(READ "${summary}" json)
string(JSON moving GET "${json}" dynamic_leak moving_keypoints)
string(JSON kept GET "${json}" dynamic_leak moving_kept)
if(NOT moving GREATER 0 OR NOT moving EQUAL kept)
  message(FATAL_ERROR "mode none: ${kept} of ${moving} moving keypoints kept, expected all of at least one")
endif()
string(JSON rate GET "${json}" dynamic_leak rate)
if(NOT rate MATCHES "^1(\\.0*)?$")
  message(FATAL_ERROR "mode none: the leak rate is ${rate}, expected 1")
endif()
moving_columns("${WORK}/rendered/frames.csv" rendered_pairs)
set(sum 0)
foreach(pair IN LISTS rendered_pairs)
  string(REPLACE "/" ";" ab "${pair}")
  list(GET ab 0 a)
  list(GET ab 1 b)
  if(NOT a EQUAL b OR a LESS 0)
    message(FATAL_ERROR "mode none: frames.csv row ${pair} keeps fewer than it has, or has no ground truth")
  endif()
  math(EXPR sum "${sum} + ${a}")
endforeach()
if(NOT sum EQUAL moving)
  message(FATAL_ERROR "summary.json moving_keypoints ${moving} is not the sum ${sum} of frames.csv")
endif()
# A rendered run without --vocabulary closes loops with one trained on another preset.
expect_json("${summary}" ON loop_settings enabled)
expect_json("${summary}" "walking_halfsphere rendered, seed 4, .*not the evaluated frames.*" loop_settings vocabulary)
expect_json("${summary}" all loop_settings cge_ties)
expect_json("${summary}" combined loop_settings scoring)
expect_json("${summary}" "0\\.50*" loop_settings min_score)
expect_json("${summary}" min_cge_score loop_settings min_score_setting)
expect_json("${summary}" normalised loop_settings cge_scaling)
expect_json("${summary}" "0\\.0030*1?" mapping_settings tracking_depth_sigma)
expect_json("${summary}" "0\\.0030*1?" mapping_settings ba_depth_sigma)
expect_json("${summary}" on mapping_settings local_ba)
expect_json("${summary}" 20 mapping_settings local_ba_window)
expect_json("${summary}" 10 mapping_settings local_ba_fixed)
expect_json("${summary}" 3 mapping_settings reference_min_observations)
expect_json("${summary}" 5 mapping_settings keyframe_min_gap)
expect_json("${summary}" 2 mapping_settings orb_spread)
expect_json("${summary}" all mapping_settings map_maintenance)
expect_json("${summary}" 10 mapping_settings keyframe_interval)
expect_json("${summary}" pgo\\+ba mapping_settings loop_correction)
expect_json("${summary}" pose_lm mapping_settings tracking_solver)
expect_json("${summary}" rigid mapping_settings tracking_ransac_solver)
expect_json("${summary}" schur_lm mapping_settings local_ba_solver)
expect_json("${summary}" schur_lm mapping_settings global_ba_solver)
file(READ "${WORK}/rendered/trajectory.txt" default_trajectory)

# 1b. The tracking and local-BA flags reach the run: each is recorded and changes the trajectory
#     (mode none makes a keyframe almost every frame, so the local BA runs in these frames).
run_tool(0 "${EXE}" ${common} --mode none --tracking-depth-sigma 0 --out "${WORK}/pixels_only")
expect_json("${WORK}/pixels_only/summary.json" "0(\\.0*)?" mapping_settings tracking_depth_sigma)
file(READ "${WORK}/pixels_only/trajectory.txt" trajectory)
if(trajectory STREQUAL default_trajectory)
  message(FATAL_ERROR "--tracking-depth-sigma 0 left the trajectory unchanged")
endif()
# The Ceres backend of the refinement reaches the run (the same optimum: the trajectory need not change).
run_tool(0 "${EXE}" ${common} --mode none --tracking-solver ceres --out "${WORK}/ceres_tracking")
expect_json("${WORK}/ceres_tracking/summary.json" ceres mapping_settings tracking_solver)
# EPnP hypotheses reach the run and take another path to the pose.
run_tool(0 "${EXE}" ${common} --mode none --tracking-ransac-solver epnp --out "${WORK}/epnp_tracking")
expect_json("${WORK}/epnp_tracking/summary.json" epnp mapping_settings tracking_ransac_solver)
file(READ "${WORK}/epnp_tracking/trajectory.txt" trajectory)
if(trajectory STREQUAL default_trajectory)
  message(FATAL_ERROR "--tracking-ransac-solver epnp left the trajectory unchanged")
endif()
run_tool(0 "${EXE}" ${common} --mode none --global-ba-solver ceres --out "${WORK}/ceres_global_ba")
expect_json("${WORK}/ceres_global_ba/summary.json" ceres mapping_settings global_ba_solver)
run_tool(0 "${EXE}" ${common} --mode none --local-ba off --local-ba-window 3 --local-ba-fixed 0
         --out "${WORK}/no_local_ba")
set(summary "${WORK}/no_local_ba/summary.json")
expect_json("${summary}" off mapping_settings local_ba)
expect_json("${summary}" 3 mapping_settings local_ba_window)
expect_json("${summary}" 0 mapping_settings local_ba_fixed)
file(READ "${WORK}/no_local_ba/trajectory.txt" trajectory)
if(trajectory STREQUAL default_trajectory)
  message(FATAL_ERROR "--local-ba off left the trajectory unchanged")
endif()

# 1c. --keyframe-interval reaches the patch selector of mode YMK: recorded, and with k = 1 the
#     best candidate of every frame's interval is inserted, so the keyframes change.
#     (cv::ORB's own keypoints: spread ones keep the first frames' patch histograms too close to
#     the first keyframe's for any candidate.)
run_tool(0 "${EXE}" ${common} --orb-spread 1 --mode YMK --out "${WORK}/ymk_default")
run_tool(0 "${EXE}" ${common} --orb-spread 1 --mode YMK --keyframe-interval 1 --out "${WORK}/ymk_interval_1")
expect_json("${WORK}/ymk_interval_1/summary.json" 1 mapping_settings keyframe_interval)
file(READ "${WORK}/ymk_default/keyframes.txt" default_keyframes)
file(READ "${WORK}/ymk_interval_1/keyframes.txt" keyframes)
if(keyframes STREQUAL default_keyframes)
  message(FATAL_ERROR "--keyframe-interval 1 left the keyframes unchanged")
endif()
run_tool(2 "${EXE}" ${common} --keyframe-interval 0 --out "${WORK}/ymk_interval_0")
# --semantic-change-frames is recorded (default 1, the paper's rule); 0 is refused.
expect_json("${WORK}/ymk_default/summary.json" 1 mapping_settings semantic_change_frames)
expect_json("${WORK}/ymk_default/summary.json" 0 mapping_settings local_ba_iterations_per_frame)
run_tool(0 "${EXE}" ${common} --orb-spread 1 --mode YMK --semantic-change-frames 4 --out "${WORK}/ymk_hold_4")
expect_json("${WORK}/ymk_hold_4/summary.json" 4 mapping_settings semantic_change_frames)
run_tool(2 "${EXE}" ${common} --semantic-change-frames 0 --out "${WORK}/ymk_hold_0")

# 2.
run_tool(0 "${EXE}" ${common} --mode none --loop-scoring bow_only --loop-min-score 0.1 --cge-scaling raw
         --cge-ties min --out "${WORK}/settings")
set(summary "${WORK}/settings/summary.json")
expect_json("${summary}" bow_only loop_settings scoring)
expect_json("${summary}" "0\\.10*1?" loop_settings min_score)
expect_json("${summary}" min_bow_score loop_settings min_score_setting)
expect_json("${summary}" raw loop_settings cge_scaling)
expect_json("${summary}" min loop_settings cge_ties)

# 3.
if(DEFINED SIM)
  run_tool(0 "${SIM}" --preset walking_xyz ${common} --out "${WORK}/sequence")
  run_tool(0 "${EXE}" --dataset "${WORK}/sequence" --mode none --out "${WORK}/folder")
  # A dataset run without --vocabulary closes no loops, and says so.
  expect_json("${WORK}/folder/summary.json" OFF loop_settings enabled)
  expect_json("${WORK}/folder/summary.json" "none given: loop closing off.*" loop_settings vocabulary)
  expect_json("${WORK}/folder/summary.json" ${frames} dynamic_leak frames_with_ground_truth)
  moving_columns("${WORK}/folder/frames.csv" folder_pairs)
  if(NOT folder_pairs STREQUAL rendered_pairs)
    message(FATAL_ERROR "moving counts from masks/ (${folder_pairs}) differ from the renderer's (${rendered_pairs})")
  endif()
  file(REMOVE "${WORK}/sequence/masks/instances.csv")
  run_tool(0 "${EXE}" --dataset "${WORK}/sequence" --mode none --out "${WORK}/no_truth")
  expect_json("${WORK}/no_truth/summary.json" 0 dynamic_leak frames_with_ground_truth)
  file(READ "${WORK}/no_truth/summary.json" json)
  string(JSON rate_type TYPE "${json}" dynamic_leak rate)
  if(NOT rate_type STREQUAL "NULL")
    message(FATAL_ERROR "without ground truth the leak rate is of type ${rate_type}, expected null")
  endif()
  # The depth weight comes from the settings file (the renderer's cge.DepthSigmaPerMetre, else
  # ORB-SLAM2's 1 / bf); --tracking-depth-sigma, when given, wins over the file for tracking.
  expect_json("${WORK}/folder/summary.json" "0\\.0030*1?" mapping_settings ba_depth_sigma)
  file(READ "${WORK}/sequence/camera.yaml" camera_yaml)
  string(REGEX REPLACE "cge\\.DepthSigmaPerMetre:[^\n]*\n" "" camera_yaml "${camera_yaml}")
  file(WRITE "${WORK}/orbslam2_camera.yaml" "${camera_yaml}")
  run_tool(0 "${EXE}" --dataset "${WORK}/sequence" --settings "${WORK}/orbslam2_camera.yaml" --mode none --frames 5
           --tracking-depth-sigma 0.005 --out "${WORK}/orbslam2_weight")
  expect_json("${WORK}/orbslam2_weight/summary.json" "0\\.0250*1?" mapping_settings ba_depth_sigma)
  expect_json("${WORK}/orbslam2_weight/summary.json" "0\\.0050*1?" mapping_settings tracking_depth_sigma)
  moving_columns("${WORK}/no_truth/frames.csv" none_pairs)
  foreach(pair IN LISTS none_pairs)
    if(NOT pair STREQUAL "-1/-1")
      message(FATAL_ERROR "without ground truth frames.csv has ${pair}, expected -1/-1")
    endif()
  endforeach()
endif()
file(REMOVE_RECURSE "${WORK}")
