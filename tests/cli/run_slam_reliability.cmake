# cge_slam's output folder under failure: a failed or killed run leaves --out as it was.
#   cmake -DEXE=<cge_slam> -DWORK=<a folder of this test's own in the build tree> -P run_slam_reliability.cmake
# 1. --force into a folder where summary.json is a user's folder: refused before the run (exit 2),
#    nothing moved in (once trajectory.txt and frames.csv were moved before the failure);
# 2. SIGTERM during a run: the staging folder is removed, and so is the --out folder the run made;
# 3. a staging folder of a process that is gone (a killed run's leftover) does not make --out "not
#    empty" and is removed by the next run;
# 4. missing folders on the way to --out are created; a failing run removes those it created.
cmake_minimum_required(VERSION 3.16)
foreach(var EXE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_slam_reliability.cmake: ${var} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(run_args --mode none --frames 2)

# 1.
file(MAKE_DIRECTORY "${WORK}/user/summary.json")
file(WRITE "${WORK}/user/notes.txt" "the user's file\n")
execute_process(COMMAND "${EXE}" ${run_args} --out "${WORK}/user" --force
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT rc EQUAL 2 OR NOT err MATCHES "summary\\.json' exists and is not a file")
  message(FATAL_ERROR "1: a folder named summary.json: exit ${rc}, expected 2 naming it\n${err}")
endif()
file(GLOB entries RELATIVE "${WORK}/user" "${WORK}/user/*" "${WORK}/user/.*")
list(SORT entries)
if(NOT entries STREQUAL "notes.txt;summary.json")
  message(FATAL_ERROR "1: the refused run changed --out: ${entries}")
endif()

# 2. The default run renders 300 frames (many seconds): SIGTERM once its staging folder exists.
set(killed "${WORK}/killed")
execute_process(
  COMMAND /bin/sh -c "\"$0\" --mode none --out \"$1\" >/dev/null 2>&1 & pid=$!
    i=0
    while [ ! -d \"$1/.cge_slam.partial.$pid\" ] && [ $i -lt 600 ]; do sleep 0.05; i=$((i + 1)); done
    [ -d \"$1/.cge_slam.partial.$pid\" ] || { kill -9 $pid; echo no-staging-folder; exit 0; }
    kill -TERM $pid; wait $pid; echo \"status $?\"" "${EXE}" "${killed}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT out MATCHES "status 143")
  message(FATAL_ERROR "2: SIGTERM: ${out}${err}")
endif()
if(EXISTS "${killed}")
  file(GLOB_RECURSE left "${killed}/*" "${killed}/.*")
  message(FATAL_ERROR "2: the killed run left ${killed} behind: ${left}")
endif()

# 3.
set(stale "${WORK}/stale/.cge_slam.partial.999999999")
file(MAKE_DIRECTORY "${stale}")
file(WRITE "${stale}/trajectory.txt" "a killed run's file\n")
execute_process(COMMAND "${EXE}" ${run_args} --out "${WORK}/stale"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "3: a stale staging folder made the run fail (exit ${rc}):\n${err}")
endif()
if(EXISTS "${stale}" OR NOT EXISTS "${WORK}/stale/trajectory.txt")
  message(FATAL_ERROR "3: the stale staging folder was not removed, or the run wrote nothing")
endif()

# 4.
execute_process(COMMAND "${EXE}" ${run_args} --out "${WORK}/new/deeper/run"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT rc EQUAL 0 OR NOT EXISTS "${WORK}/new/deeper/run/summary.json")
  message(FATAL_ERROR "4: missing parent folders: exit ${rc}\n${err}")
endif()
execute_process(COMMAND "${EXE}" --dataset "${CMAKE_CURRENT_LIST_DIR}/slam_missing_image" --mode none
                        --out "${WORK}/failed/deeper/run"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT rc EQUAL 2 OR EXISTS "${WORK}/failed")
  message(FATAL_ERROR "4: a failing run: exit ${rc} (expected 2), and it must not leave ${WORK}/failed\n${err}")
endif()
