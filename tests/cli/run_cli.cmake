# Runs one command-line test: a program, its arguments and standard input, then checks the exit
# code and the output. Script mode:
#   cmake -DEXE=<program> [-DARG_1=<arg> -DARG_2=<arg> ...] [-DSTDIN=<file>] [-DEXIT=<code>]
#         [-DSTDOUT_1=<regex> ...] [-DSTDOUT_NOT_1=<regex> ...] [-DSTDERR_1=<regex> ...]
#         -P run_cli.cmake
# Numbered variables instead of lists, so that arguments and regexes pass through ctest unchanged.
# STDOUT_<i>: some line of standard output matches the regex as a whole (anchored ^...$).
# STDOUT_NOT_<i>: no line of standard output matches it (anchored).
# STDERR_<i>: the regex is found somewhere in standard error (not anchored).
# MEMORY_KB: run the program under `ulimit -v MEMORY_KB` (through /bin/sh), for inputs that once
# exhausted memory.
# EXIT defaults to 0. A failing run (EXIT != 0) must say something on stderr and nothing on stdout.
# Relative paths are taken from the working directory ctest runs the test in.
cmake_minimum_required(VERSION 3.16)

if(NOT DEFINED EXE)
  message(FATAL_ERROR "run_cli.cmake: EXE is not set")
endif()
if(NOT DEFINED EXIT)
  set(EXIT 0)
endif()

set(args)
set(i 1)
while(DEFINED ARG_${i})
  list(APPEND args "${ARG_${i}}")
  math(EXPR i "${i} + 1")
endwhile()

# Never inherit ctest's standard input (a terminal would make a test wait for typing).
if(NOT DEFINED STDIN)
  set(STDIN "${CMAKE_CURRENT_LIST_DIR}/empty.txt")
endif()

set(command "${EXE}" ${args})
if(DEFINED MEMORY_KB)
  set(command /bin/sh -c "ulimit -v ${MEMORY_KB} && exec \"$0\" \"$@\"" "${EXE}" ${args})
endif()
execute_process(COMMAND ${command}
                INPUT_FILE "${STDIN}"
                RESULT_VARIABLE rc
                OUTPUT_VARIABLE out
                ERROR_VARIABLE err
                TIMEOUT 120)

set(failures "")
if(NOT "${rc}" STREQUAL "${EXIT}")
  string(APPEND failures "  exit code ${rc}, expected ${EXIT}\n")
endif()
if(NOT EXIT EQUAL 0)
  if(err STREQUAL "")
    string(APPEND failures "  nothing on stderr for a failing run\n")
  endif()
  if(NOT out STREQUAL "")
    string(APPEND failures "  output on stdout for a failing run\n")
  endif()
endif()

# One list element per line of stdout (the tool's output holds no ';'). Square brackets would
# join the lines between them into one element (CMake's list syntax), so they are stored as
# placeholders and restored line by line (restore_brackets).
string(REGEX REPLACE "\n$" "" out_lines "${out}")
string(REPLACE "[" "<cge-lsb>" out_lines "${out_lines}")
string(REPLACE "]" "<cge-rsb>" out_lines "${out_lines}")
string(REPLACE "\n" ";" out_lines "${out_lines}")
macro(restore_brackets var)
  string(REPLACE "<cge-lsb>" "[" ${var} "${${var}}")
  string(REPLACE "<cge-rsb>" "]" ${var} "${${var}}")
endmacro()

set(i 1)
while(DEFINED STDOUT_${i})
  set(found FALSE)
  foreach(line IN LISTS out_lines)
    restore_brackets(line)
    if(line MATCHES "^${STDOUT_${i}}$")
      set(found TRUE)
      break()
    endif()
  endforeach()
  if(NOT found)
    string(APPEND failures "  no line of stdout matches '${STDOUT_${i}}'\n")
  endif()
  math(EXPR i "${i} + 1")
endwhile()

set(i 1)
while(DEFINED STDOUT_NOT_${i})
  foreach(line IN LISTS out_lines)
    restore_brackets(line)
    if(line MATCHES "^${STDOUT_NOT_${i}}$")
      string(APPEND failures "  stdout line '${line}' matches '${STDOUT_NOT_${i}}' but must not\n")
    endif()
  endforeach()
  math(EXPR i "${i} + 1")
endwhile()

set(i 1)
while(DEFINED STDERR_${i})
  if(NOT err MATCHES "${STDERR_${i}}")
    string(APPEND failures "  stderr does not match '${STDERR_${i}}'\n")
  endif()
  math(EXPR i "${i} + 1")
endwhile()

if(NOT failures STREQUAL "")
  string(REPLACE ";" " " shown_args "${args}")
  message(FATAL_ERROR "${EXE} ${shown_args} < ${STDIN}\n${failures}--- stdout ---\n${out}--- stderr ---\n${err}")
endif()
