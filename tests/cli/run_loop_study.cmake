# Command-line test of cge_loop_study on a short rendered loop sequence:
#   cmake -DEXE=<cge_loop_study> -DSIM=<cge_sim> -DTESTS=<cge_tests> -DWORK=<a folder of its own> \
#         -P run_loop_study.cmake
# 1. cge_sim renders loop_dynamic (FRAMES frames, seed 1); the study runs on it twice: same bytes
#    in frames.csv, pairs.csv, summary.json and on standard output;
# 2. cge_tests "[.loop_study_files]" recomputes the printed figures from the CSV files (brute-force
#    AUC and AP, collapse flags from the entropy columns, revisit labels from loops.txt);
# 3. a non-empty --out is refused without --force and left alone; with --force a user's file stays;
# 4. bad input (no masks/ in the dataset) exits 2, naming what is missing.
cmake_minimum_required(VERSION 3.16)

foreach(var EXE SIM TESTS WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_loop_study.cmake: ${var} is not set")
  endif()
endforeach()

set(frames 60)
set(step 2)
set(gap 10)
set(tolerance 1)
file(REMOVE_RECURSE "${WORK}")  # this test's own folder from an earlier run
file(MAKE_DIRECTORY "${WORK}")

execute_process(COMMAND "${SIM}" --preset loop_dynamic --frames ${frames} --seed 1 --out "${WORK}/seq"
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err TIMEOUT 600)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cge_sim failed: ${err}")
endif()

function(run_study expected_rc stdout_file)
  execute_process(COMMAND "${EXE}" ${ARGN} INPUT_FILE "${CMAKE_CURRENT_LIST_DIR}/empty.txt"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 600)
  if(NOT "${rc}" STREQUAL "${expected_rc}")
    message(FATAL_ERROR "cge_loop_study ${ARGN}: exit code ${rc}, expected ${expected_rc}\n"
                        "--- stdout ---\n${out}--- stderr ---\n${err}")
  endif()
  if(stdout_file)
    file(WRITE "${stdout_file}" "${out}")
  endif()
  set(last_stderr "${err}" PARENT_SCOPE)
endfunction()

set(args --dataset "${WORK}/seq" --step ${step} --min-gap-frames ${gap} --collapse-tolerance-bits ${tolerance})
run_study(0 "${WORK}/a.stdout" ${args} --out "${WORK}/a")
run_study(0 "${WORK}/b.stdout" ${args} --out "${WORK}/b")
foreach(name frames.csv pairs.csv summary.json)
  file(SHA256 "${WORK}/a/${name}" ha)
  file(SHA256 "${WORK}/b/${name}" hb)
  if(NOT ha STREQUAL hb)
    message(FATAL_ERROR "${name} differs between two runs with the same arguments")
  endif()
endforeach()
file(READ "${WORK}/a.stdout" sa)
file(READ "${WORK}/b.stdout" sb)
if(NOT sa STREQUAL sb)
  message(FATAL_ERROR "standard output differs between two runs:\n${sa}---\n${sb}")
endif()
foreach(name frames pairs revisit_pairs collapse_fraction_raw collapse_fraction_normalised auc_raw auc_normalised
             average_precision_raw average_precision_normalised)
  if(NOT sa MATCHES "(^|\n)${name} [-+0-9.e]+\n")
    message(FATAL_ERROR "standard output has no number for ${name}:\n${sa}")
  endif()
endforeach()

execute_process(COMMAND ${CMAKE_COMMAND} -E env "CGE_LOOP_STUDY_OUT=${WORK}/a" "CGE_LOOP_STUDY_STDOUT=${WORK}/a.stdout"
                        "CGE_LOOP_STUDY_LOOPS=${WORK}/seq/loops.txt" "CGE_LOOP_STUDY_STEP=${step}"
                        "CGE_LOOP_STUDY_MIN_GAP=${gap}" "CGE_LOOP_STUDY_TOLERANCE=${tolerance}"
                        "${TESTS}" "[.loop_study_files]"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the recomputation from the output files failed:\n${out}${err}")
endif()

file(MAKE_DIRECTORY "${WORK}/forced")
file(WRITE "${WORK}/forced/user_notes.txt" "keep me\n")
run_study(2 "" ${args} --out "${WORK}/forced")
if(NOT last_stderr MATCHES "not empty")
  message(FATAL_ERROR "the refusal does not say the folder is not empty: ${last_stderr}")
endif()
file(GLOB forced_files RELATIVE "${WORK}/forced" "${WORK}/forced/*" "${WORK}/forced/.*")
if(NOT forced_files STREQUAL "user_notes.txt")
  message(FATAL_ERROR "a refused run changed the folder: ${forced_files}")
endif()
run_study(0 "" ${args} --out "${WORK}/forced" --force)
file(READ "${WORK}/forced/user_notes.txt" kept)
if(NOT kept STREQUAL "keep me\n")
  message(FATAL_ERROR "--force changed or removed the user's file")
endif()
file(SHA256 "${WORK}/forced/pairs.csv" hf)
file(SHA256 "${WORK}/a/pairs.csv" ha)
if(NOT hf STREQUAL ha)
  message(FATAL_ERROR "pairs.csv written with --force differs from the first run's")
endif()

file(REMOVE_RECURSE "${WORK}/seq/masks")
run_study(2 "" ${args} --out "${WORK}/no_masks")
if(NOT last_stderr MATCHES "masks.*instances\\.csv")
  message(FATAL_ERROR "the error does not name the missing masks: ${last_stderr}")
endif()
if(EXISTS "${WORK}/no_masks")
  message(FATAL_ERROR "a failed run created its output folder")
endif()
file(REMOVE_RECURSE "${WORK}")
