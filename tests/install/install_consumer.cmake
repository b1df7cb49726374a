# The two steps of the install/consumer test (tests/install/CMakeLists.txt), in script mode:
#   cmake -DSTEP=install  -DBUILD_DIR=<build> -DPREFIX=<dir> [-DCONFIG=<cfg>] -P install_consumer.cmake
#       a fresh `cmake --install <build> --prefix <dir>`, then checks the package files are there;
#   cmake -DSTEP=consumer -DPREFIX=<dir> -DSOURCE_DIR=<examples/consumer> -DBINARY_DIR=<dir>
#         [-DCONFIG=<cfg>] [-DEXPECTED_VERSION=<v>] [-DGENERATOR=... -DGENERATOR_PLATFORM=...
#         -DGENERATOR_TOOLSET=... -DMAKE_PROGRAM=... -DCXX_COMPILER=... -DEIGEN3_DIR=...]
#       configures the consumer in a fresh directory with CMAKE_PREFIX_PATH=<dir> (and no package
#       registries, so that nothing but the installed tree can satisfy find_package(cge)), checks
#       that it found the package under <dir>, builds it and runs it (it exits 0 when its P5 check
#       passes).
cmake_minimum_required(VERSION 3.16)

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "${what} failed (${rc}):\n${cmd}\n--- stdout ---\n${out}\n--- stderr ---\n${err}")
  endif()
  set(step_output "${out}${err}" PARENT_SCOPE)
endfunction()

foreach(var STEP PREFIX)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "install_consumer.cmake: ${var} is not set")
  endif()
endforeach()
set(config_args)
if(NOT "${CONFIG}" STREQUAL "")
  set(config_args --config "${CONFIG}")
endif()

if(STEP STREQUAL "install")
  file(REMOVE_RECURSE "${PREFIX}")  # no files left over from an earlier run
  run_step("cmake --install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}" ${config_args})
  file(GLOB_RECURSE config_files "${PREFIX}/*/cgeConfig.cmake")
  file(GLOB_RECURSE version_files "${PREFIX}/*/cgeConfigVersion.cmake")
  file(GLOB_RECURSE target_files "${PREFIX}/*/cgeTargets.cmake")
  foreach(what config_files version_files target_files)
    if(NOT ${what})
      message(FATAL_ERROR "the install into ${PREFIX} has no ${what}")
    endif()
  endforeach()
  foreach(header cge/cge.hpp cge/io/graph_text.hpp cge/graph/graph.hpp)
    if(NOT EXISTS "${PREFIX}/include/${header}")
      message(FATAL_ERROR "the install into ${PREFIX} lacks include/${header}")
    endif()
  endforeach()
  message(STATUS "installed cge into ${PREFIX}")

elseif(STEP STREQUAL "consumer")
  file(REMOVE_RECURSE "${BINARY_DIR}")  # configure from scratch every time
  set(configure "${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${BINARY_DIR}" "-DCMAKE_PREFIX_PATH=${PREFIX}"
                -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF)
  if(NOT "${GENERATOR}" STREQUAL "")
    list(APPEND configure -G "${GENERATOR}")
  endif()
  if(NOT "${GENERATOR_PLATFORM}" STREQUAL "")
    list(APPEND configure -A "${GENERATOR_PLATFORM}")
  endif()
  if(NOT "${GENERATOR_TOOLSET}" STREQUAL "")
    list(APPEND configure -T "${GENERATOR_TOOLSET}")
  endif()
  if(NOT "${MAKE_PROGRAM}" STREQUAL "")
    list(APPEND configure "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
  endif()
  if(NOT "${CXX_COMPILER}" STREQUAL "")
    list(APPEND configure "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
  endif()
  if(NOT "${EIGEN3_DIR}" STREQUAL "")
    list(APPEND configure "-DEigen3_DIR=${EIGEN3_DIR}")  # the Eigen the build used
  endif()
  if(NOT "${CONFIG}" STREQUAL "")
    list(APPEND configure "-DCMAKE_BUILD_TYPE=${CONFIG}")
  endif()
  run_step("configuring the consumer" ${configure})

  # The consumer prints "Found cge <version> in <cge_DIR>": it must be the installed package.
  if(NOT step_output MATCHES "Found cge ([^ ]*) in ([^\n]*)")
    message(FATAL_ERROR "the consumer did not report the cge package it found:\n${step_output}")
  endif()
  set(found_version "${CMAKE_MATCH_1}")
  get_filename_component(found_dir "${CMAKE_MATCH_2}" REALPATH)
  get_filename_component(real_prefix "${PREFIX}" REALPATH)
  string(FIND "${found_dir}/" "${real_prefix}/" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "the consumer found cge in ${found_dir}, not under the test prefix ${real_prefix}")
  endif()
  if(DEFINED EXPECTED_VERSION AND NOT found_version STREQUAL EXPECTED_VERSION)
    message(FATAL_ERROR "the consumer found cge ${found_version}, expected ${EXPECTED_VERSION}")
  endif()

  run_step("building the consumer" "${CMAKE_COMMAND}" --build "${BINARY_DIR}" ${config_args})

  set(exe "")
  foreach(candidate "${BINARY_DIR}/cge_consumer" "${BINARY_DIR}/cge_consumer.exe" "${BINARY_DIR}/${CONFIG}/cge_consumer"
                    "${BINARY_DIR}/${CONFIG}/cge_consumer.exe")
    if(EXISTS "${candidate}" AND NOT IS_DIRECTORY "${candidate}")
      set(exe "${candidate}")
      break()
    endif()
  endforeach()
  if(exe STREQUAL "")
    message(FATAL_ERROR "the consumer was built but its executable is not in ${BINARY_DIR}")
  endif()
  run_step("running the consumer" "${exe}")
  message(STATUS "${step_output}")

else()
  message(FATAL_ERROR "install_consumer.cmake: unknown STEP '${STEP}' (install or consumer)")
endif()
