# The one rule for output locations (docs/CLI.md, "Output files and folders"): every tool creates
# the missing folders on the way to an output, as cge_slam and cge_sim always did (cge_vocab once
# refused with exit 2, cge_frontend failed with exit 1).
#   cmake -DWORK=<folder> [-DEVAL=<cge_eval>] [-DVOCAB=<cge_vocab>] [-DFRONTEND=<cge_frontend>]
#         [-DSIM=<cge_sim>] -P run_output_folders.cmake   (run in tests/cli)
cmake_minimum_required(VERSION 3.16)
if(NOT DEFINED WORK)
  message(FATAL_ERROR "run_output_folders.cmake: WORK is not set")
endif()
file(REMOVE_RECURSE "${WORK}")

function(expect_output name file)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
  if(NOT rc EQUAL 0 OR NOT EXISTS "${file}")
    message(FATAL_ERROR "${name}: exit ${rc}, expected 0 and ${file}\n${err}")
  endif()
  get_filename_component(folder "${file}" DIRECTORY)
  file(GLOB partial "${folder}/.*partial*")
  if(partial)
    message(FATAL_ERROR "${name}: temporary files left: ${partial}")
  endif()
endfunction()

if(DEFINED EVAL)
  expect_output(cge_eval "${WORK}/eval/a/b/aligned.csv"
                "${EVAL}" ate eval/gt.txt eval/est.txt --aligned-out "${WORK}/eval/a/b/aligned.csv")
  # A refused run creates nothing.
  execute_process(COMMAND "${EVAL}" ate eval/gt_two_poses.txt eval/est.txt --aligned-out "${WORK}/refused/a/x.csv"
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET TIMEOUT 60)
  if(NOT rc EQUAL 2 OR EXISTS "${WORK}/refused")
    message(FATAL_ERROR "cge_eval: a refused run: exit ${rc} (expected 2), and ${WORK}/refused must not exist")
  endif()
endif()
if(DEFINED VOCAB)
  expect_output(cge_vocab "${WORK}/vocab/a/b/voc.txt"
                "${VOCAB}" --preset walking_xyz --frames 1 -L 1 --out "${WORK}/vocab/a/b/voc.txt")
endif()
if(DEFINED FRONTEND)
  expect_output(cge_frontend "${WORK}/frontend/a/b/picture.png"
                "${FRONTEND}" --rgb frontend/rgb.png --depth frontend/depth.png --masks frontend/masks/frame.png
                --out-image "${WORK}/frontend/a/b/picture.png")
endif()
if(DEFINED SIM)
  expect_output(cge_sim "${WORK}/sim/a/b/seq/rgb.txt"
                "${SIM}" --preset walking_xyz --frames 1 --out "${WORK}/sim/a/b/seq")
endif()
