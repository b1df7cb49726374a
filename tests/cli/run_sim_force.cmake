# Command-line test of cge_sim's output folder rules and determinism (needs the renderer):
#   cmake -DEXE=<cge_sim> -DWORK=<a folder of this test's own in the build tree> -P run_sim_force.cmake
# 1. a run into a fresh folder succeeds;
# 2. a run into a folder holding a user's file is refused without --force and leaves it alone;
# 3. with --force it writes the sequence and the user's file is still there, unchanged;
# 4. both runs wrote the same bytes in every file of the sequence;
# 5. --no-depth-noise changes the depth images only (and says so in the text files' header).
# 6. --walking-speed and --pause-s change the people (masks) and are recorded; their defaults given
#    explicitly change nothing; a negative pause is refused (exit 2).
# 7. a --force run whose destination is blocked moves nothing and leaves the folder as it was.
cmake_minimum_required(VERSION 3.16)

foreach(var EXE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_sim_force.cmake: ${var} is not set")
  endif()
endforeach()

set(args --preset walking_xyz --frames 3 --seed 5)
set(user_file "${WORK}/forced/user_notes.txt")
file(REMOVE_RECURSE "${WORK}")  # this test's own folder from an earlier run
file(MAKE_DIRECTORY "${WORK}/forced")
file(WRITE "${user_file}" "keep me\n")

# Sets out_var to how many of the files named after the folders differ between them.
function(count_differing out_var dir_a dir_b)
  set(differing 0)
  foreach(name IN LISTS ARGN)
    file(SHA256 "${dir_a}/${name}" a)
    file(SHA256 "${dir_b}/${name}" b)
    if(NOT a STREQUAL b)
      math(EXPR differing "${differing} + 1")
    endif()
  endforeach()
  set(${out_var} ${differing} PARENT_SCOPE)
endfunction()

# Fails unless the text file `name` of folder `dir` matches `pattern` (its header records a flag).
function(require_recorded dir name pattern)
  file(READ "${dir}/${name}" header)
  if(NOT header MATCHES "${pattern}")
    message(FATAL_ERROR "${name} in ${dir} does not record ${pattern}:\n${header}")
  endif()
endfunction()

function(run_sim expected_rc)
  execute_process(COMMAND "${EXE}" ${args} ${ARGN} INPUT_FILE "${CMAKE_CURRENT_LIST_DIR}/empty.txt"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
  if(NOT "${rc}" STREQUAL "${expected_rc}")
    message(FATAL_ERROR "cge_sim ${args} ${ARGN}: exit code ${rc}, expected ${expected_rc}\n"
                        "--- stdout ---\n${out}--- stderr ---\n${err}")
  endif()
  set(last_stderr "${err}" PARENT_SCOPE)
endfunction()

run_sim(0 --out "${WORK}/fresh")
run_sim(2 --out "${WORK}/forced")
if(NOT last_stderr MATCHES "not empty")
  message(FATAL_ERROR "the refusal does not say the folder is not empty: ${last_stderr}")
endif()
file(GLOB forced_files RELATIVE "${WORK}/forced" "${WORK}/forced/*")
if(NOT forced_files STREQUAL "user_notes.txt")
  message(FATAL_ERROR "a refused run changed the folder: ${forced_files}")
endif()
run_sim(0 --out "${WORK}/forced" --force)

file(READ "${user_file}" kept)
if(NOT kept STREQUAL "keep me\n")
  message(FATAL_ERROR "--force changed or removed the user's file")
endif()

file(GLOB_RECURSE written RELATIVE "${WORK}/fresh" "${WORK}/fresh/*")
list(LENGTH written count)
if(count LESS 20)  # 4 images per frame and 8 text files
  message(FATAL_ERROR "the fresh run wrote only ${count} files: ${written}")
endif()
foreach(name IN LISTS written)
  file(SHA256 "${WORK}/fresh/${name}" a)
  if(NOT EXISTS "${WORK}/forced/${name}")
    message(FATAL_ERROR "the forced run did not write ${name}")
  endif()
  file(SHA256 "${WORK}/forced/${name}" b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "${name} differs between two runs with the same arguments")
  endif()
endforeach()

# 5. Without the depth noise: the same colour images, other depth images, and a header that says so.
run_sim(0 --out "${WORK}/no_noise" --no-depth-noise)
file(GLOB depth_images RELATIVE "${WORK}/fresh" "${WORK}/fresh/depth/*.png")
file(GLOB rgb_images RELATIVE "${WORK}/fresh" "${WORK}/fresh/rgb/*.png")
count_differing(rgb_changed "${WORK}/fresh" "${WORK}/no_noise" ${rgb_images})
if(NOT rgb_changed EQUAL 0)
  message(FATAL_ERROR "--no-depth-noise changed ${rgb_changed} colour images")
endif()
count_differing(depth_changed "${WORK}/fresh" "${WORK}/no_noise" ${depth_images})
list(LENGTH depth_images depth_count)
if(NOT depth_changed EQUAL depth_count OR depth_count EQUAL 0)
  message(FATAL_ERROR "--no-depth-noise changed ${depth_changed} of ${depth_count} depth images, expected all")
endif()
require_recorded("${WORK}/no_noise" depth.txt "--no-depth-noise")

# 6. --walking-speed and --pause-s move the people: other masks, the header records both flags;
#    with the defaults given explicitly, the bytes of the default run and a header without them.
run_sim(0 --out "${WORK}/slow_people" --walking-speed 0.35 --pause-s 4)
file(GLOB mask_images RELATIVE "${WORK}/fresh" "${WORK}/fresh/masks/*.png")
count_differing(masks_changed "${WORK}/fresh" "${WORK}/slow_people" ${mask_images})
if(masks_changed EQUAL 0)
  message(FATAL_ERROR "--walking-speed 0.35 --pause-s 4 changed no person mask")
endif()
require_recorded("${WORK}/slow_people" rgb.txt "--walking-speed 0\\.35 --pause-s 4")
run_sim(0 --out "${WORK}/explicit_defaults" --walking-speed 1 --pause-s 1.5)
count_differing(defaults_changed "${WORK}/fresh" "${WORK}/explicit_defaults" ${written})
if(NOT defaults_changed EQUAL 0)
  message(FATAL_ERROR "${defaults_changed} files differ with the default people motions given explicitly")
endif()
run_sim(2 --out "${WORK}/bad_pause" --pause-s -1)

# 7. All or nothing: with --force, a destination blocked by a folder of a file's name fails with
#    exit 2 naming it, and the folder is as it was (the user's file, the blocking folder, nothing
#    else, no staging folder).
file(MAKE_DIRECTORY "${WORK}/blocked/groundtruth.txt")
file(WRITE "${WORK}/blocked/user_notes.txt" "keep me\n")
run_sim(2 --out "${WORK}/blocked" --force)
if(NOT last_stderr MATCHES "groundtruth\\.txt' is a folder where a file goes")
  message(FATAL_ERROR "the blocked run does not name the blocked destination: ${last_stderr}")
endif()
file(GLOB blocked_entries RELATIVE "${WORK}/blocked" LIST_DIRECTORIES true "${WORK}/blocked/*" "${WORK}/blocked/.*")
list(SORT blocked_entries)
if(NOT blocked_entries STREQUAL "groundtruth.txt;user_notes.txt")
  message(FATAL_ERROR "a failed --force run changed the folder: ${blocked_entries}")
endif()
file(READ "${WORK}/blocked/user_notes.txt" kept)
if(NOT kept STREQUAL "keep me\n")
  message(FATAL_ERROR "a failed --force run changed the user's file")
endif()
