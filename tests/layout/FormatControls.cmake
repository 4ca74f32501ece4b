# SPDX-License-Identifier: Apache-2.0
# The format check's control for include order: under .clang-format, an include
# block out of path order is a format error and the same block sorted is not.
# Fails if .clang-format stops sorting includes (SortIncludes: Never) or sorts
# across blank lines (IncludeBlocks other than Preserve would move the second
# block's include into the first). Run by CTest:
#   cmake -DSOURCE=<root> -DCLANG_FORMAT=<program> -DSCRATCH=<dir> -P FormatControls.cmake
cmake_minimum_required(VERSION 3.25)
if(NOT SOURCE OR NOT CLANG_FORMAT OR NOT SCRATCH)
  message(FATAL_ERROR "FormatControls.cmake: give -DSOURCE=, -DCLANG_FORMAT= and -DSCRATCH=")
endif()
file(REMOVE_RECURSE ${SCRATCH})
file(MAKE_DIRECTORY ${SCRATCH})
file(COPY ${SOURCE}/.clang-format DESTINATION ${SCRATCH})
set(tail "\nint main() { return 0; }\n")
file(WRITE ${SCRATCH}/sorted.cpp "#include \"b/x.h\"\n\n#include <array>\n#include <vector>\n${tail}")
file(WRITE ${SCRATCH}/unsorted.cpp "#include \"b/x.h\"\n\n#include <vector>\n#include <array>\n${tail}")
foreach(name sorted unsorted)
  execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${name}.cpp
                  WORKING_DIRECTORY ${SCRATCH} RESULT_VARIABLE rc_${name} OUTPUT_QUIET ERROR_QUIET)
endforeach()
if(NOT rc_sorted EQUAL 0)
  message(FATAL_ERROR "a sorted include block, in two blocks, is flagged: .clang-format moves includes across blank lines")
endif()
if(rc_unsorted EQUAL 0)
  message(FATAL_ERROR "an include block out of path order passes the format check: .clang-format does not sort includes")
endif()
message(STATUS "include blocks out of path order fail the format check; sorted ones, in separate blocks, pass")
