# Command-line test of cge_slam on a short rendered sequence (no --dataset):
#   cmake -DEXE=<cge_slam> -DWORK=<a folder of this test's own in the build tree> -P run_slam.cmake
# 1. a run into a fresh folder succeeds and writes every output file;
# 2. a second run gives the same bytes in every deterministic file (not timings.csv, summary.json);
# 3. a run into a folder holding a user's file is refused without --force and leaves it alone;
#    with --force the user's file is still there, unchanged;
# 4. a run that fails on bad input (an image that cannot be read) with --force leaves the files
#    already in the folder as they were and no staging folder behind.
cmake_minimum_required(VERSION 3.16)

foreach(var EXE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_slam.cmake: ${var} is not set")
  endif()
endforeach()

set(args --frames 12 --seed 2)
file(REMOVE_RECURSE "${WORK}")  # this test's own folder from an earlier run
file(MAKE_DIRECTORY "${WORK}/forced")
set(user_file "${WORK}/forced/user_notes.txt")
file(WRITE "${user_file}" "keep me\n")

function(run_slam expected_rc)
  execute_process(COMMAND "${EXE}" ${ARGN} INPUT_FILE "${CMAKE_CURRENT_LIST_DIR}/empty.txt"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
  if(NOT "${rc}" STREQUAL "${expected_rc}")
    message(FATAL_ERROR "cge_slam ${ARGN}: exit code ${rc}, expected ${expected_rc}\n"
                        "--- stdout ---\n${out}--- stderr ---\n${err}")
  endif()
  set(last_stderr "${err}" PARENT_SCOPE)
endfunction()

run_slam(0 ${args} --out "${WORK}/a")
run_slam(0 ${args} --out "${WORK}/b")
set(deterministic trajectory.txt keyframes.txt loops.csv frames.csv groundtruth.txt)
foreach(name IN LISTS deterministic timings.csv summary.json)
  if(NOT EXISTS "${WORK}/a/${name}")
    message(FATAL_ERROR "cge_slam did not write ${name}")
  endif()
endforeach()
file(STRINGS "${WORK}/a/trajectory.txt" lines REGEX "^[0-9]")
list(LENGTH lines count)
if(NOT count EQUAL 12)
  message(FATAL_ERROR "trajectory.txt has ${count} poses, expected 12")
endif()
foreach(name IN LISTS deterministic)
  file(SHA256 "${WORK}/a/${name}" ha)
  file(SHA256 "${WORK}/b/${name}" hb)
  if(NOT ha STREQUAL hb)
    message(FATAL_ERROR "${name} differs between two runs with the same arguments")
  endif()
endforeach()

run_slam(2 ${args} --out "${WORK}/forced")
if(NOT last_stderr MATCHES "not empty")
  message(FATAL_ERROR "the refusal does not say the folder is not empty: ${last_stderr}")
endif()
file(GLOB forced_files RELATIVE "${WORK}/forced" "${WORK}/forced/*" "${WORK}/forced/.*")
if(NOT forced_files STREQUAL "user_notes.txt")
  message(FATAL_ERROR "a refused run changed the folder: ${forced_files}")
endif()
run_slam(0 ${args} --out "${WORK}/forced" --force)
file(READ "${user_file}" kept)
if(NOT kept STREQUAL "keep me\n")
  message(FATAL_ERROR "--force changed or removed the user's file")
endif()

file(SHA256 "${WORK}/forced/trajectory.txt" before)
run_slam(2 --dataset "${CMAKE_CURRENT_LIST_DIR}/slam_missing_image" --mode none --out "${WORK}/forced" --force)
if(NOT last_stderr MATCHES "0\\.000000\\.png")
  message(FATAL_ERROR "the error does not name the missing image: ${last_stderr}")
endif()
file(SHA256 "${WORK}/forced/trajectory.txt" after)
if(NOT before STREQUAL after)
  message(FATAL_ERROR "a failed run changed trajectory.txt in the output folder")
endif()
file(GLOB leftovers RELATIVE "${WORK}/forced" "${WORK}/forced/.cge_slam*")
if(leftovers)
  message(FATAL_ERROR "a failed run left its staging folder: ${leftovers}")
endif()
# 5. with a vocabulary (when cge_vocab is built), loops.csv has one decision per keyframe.
if(DEFINED VOCAB)
  execute_process(COMMAND "${VOCAB}" --preset walking_xyz --frames 4 -L 2 --out "${WORK}/vocab.txt"
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err TIMEOUT 300)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "cge_vocab failed: ${err}")
  endif()
  run_slam(0 ${args} --vocabulary "${WORK}/vocab.txt" --out "${WORK}/loops")
  file(STRINGS "${WORK}/loops/keyframes.txt" keyframes REGEX "^[0-9]")
  file(STRINGS "${WORK}/loops/loops.csv" decisions REGEX "^[0-9]")
  list(LENGTH keyframes nk)
  list(LENGTH decisions nd)
  if(NOT nk EQUAL nd OR nk EQUAL 0)
    message(FATAL_ERROR "loops.csv has ${nd} decisions for ${nk} keyframes")
  endif()
endif()
file(REMOVE_RECURSE "${WORK}")
