# SPDX-License-Identifier: Apache-2.0
# Every C++ source and header follows .clang-format (tests/README.md). Fails
# naming the files clang-format would change; run `clang-format -i <file>` on
# them. Run by CTest: cmake -DSOURCE=<root> -DCLANG_FORMAT=<program> -P Format.cmake
cmake_minimum_required(VERSION 3.25)
if(NOT SOURCE OR NOT CLANG_FORMAT)
  message(FATAL_ERROR "Format.cmake: give -DSOURCE= and -DCLANG_FORMAT=")
endif()
# Every top-level folder, listed by the walk rather than by hand, so that a new
# library is checked from its first file; build trees (a CMakeCache.txt) and
# hidden folders are not sources.
set(files "")
file(GLOB folders LIST_DIRECTORIES true RELATIVE ${SOURCE} ${SOURCE}/*)
foreach(folder IN LISTS folders)
  if(NOT IS_DIRECTORY ${SOURCE}/${folder} OR folder MATCHES "^\\." OR EXISTS ${SOURCE}/${folder}/CMakeCache.txt)
    continue()
  endif()
  file(GLOB_RECURSE found ${SOURCE}/${folder}/*.h ${SOURCE}/${folder}/*.cpp)
  list(APPEND files ${found})
endforeach()
list(LENGTH files count)
if(count LESS 100)
  message(FATAL_ERROR "Format.cmake: only ${count} sources found under ${SOURCE}: the walk is broken")
endif()
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${files}
                WORKING_DIRECTORY ${SOURCE} RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  string(REGEX MATCHALL "[^\n]*: error: code should be clang-formatted" lines "${err}")
  set(names "")
  foreach(line IN LISTS lines)
    string(REGEX REPLACE ":[0-9]+:[0-9]+: error: code should be clang-formatted" "" name "${line}")
    list(APPEND names ${name})
  endforeach()
  list(REMOVE_DUPLICATES names)
  list(JOIN names "\n  " text)
  message(FATAL_ERROR "not formatted as .clang-format says (clang-format -i fixes them):\n  ${text}")
endif()
message(STATUS "${count} sources follow .clang-format")
