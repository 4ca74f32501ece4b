# SPDX-License-Identifier: Apache-2.0
# No code, build file or document outside tests/ cites the project's issue
# tracker ("issue 27 item 3", issue "force models"): a tracker is not part of
# the repository, so such a citation points nowhere for a reader of the code.
# Code cites the docs/ section that states the rule instead (docs/style.md).
#
#   cmake -DSOURCE=<tree> -P TrackerReferences.cmake
#
# Fails naming each file and line that cites one, and fails if it read no file.
if(NOT SOURCE)
  message(FATAL_ERROR "usage: cmake -DSOURCE=<tree> -P TrackerReferences.cmake")
endif()
file(GLOB_RECURSE files RELATIVE ${SOURCE}
     ${SOURCE}/*.h ${SOURCE}/*.cpp ${SOURCE}/*.py ${SOURCE}/*.cmake ${SOURCE}/*.sh ${SOURCE}/*.md
     ${SOURCE}/*CMakeLists.txt)
set(checked 0)
set(found "")
foreach(f IN LISTS files)
  if(f MATCHES "^(build|tests|\\.git)/" OR f MATCHES "/build/")
    continue()
  endif()
  math(EXPR checked "${checked} + 1")
  file(STRINGS ${SOURCE}/${f} lines REGEX "(^|[^A-Za-z])[Ii]ssues? ([0-9]+|\")")
  foreach(line IN LISTS lines)
    string(STRIP "${line}" line)
    string(APPEND found "\n  ${f}: ${line}")
  endforeach()
endforeach()
if(checked EQUAL 0)
  message(FATAL_ERROR "no source file found under ${SOURCE}: the check read nothing")
endif()
if(found)
  message(FATAL_ERROR "tracker references (cite the docs/ section instead):${found}")
endif()
message(STATUS "${checked} files, no tracker reference")
