# SPDX-License-Identifier: BSD-3-Clause
# The Core tests' temporary folder (their TMPDIR): made empty before them (MODE=setup), and
# checked empty after them (MODE=check), so that a test that leaves a file behind fails the suite.
#   cmake -DDIR=<folder> -DMODE=setup|check -P AFAMTestScratch.cmake
if (MODE STREQUAL "setup")
  file(REMOVE_RECURSE "${DIR}")
  file(MAKE_DIRECTORY "${DIR}")
elseif (MODE STREQUAL "check")
  file(GLOB _left LIST_DIRECTORIES true "${DIR}/*")
  if (_left)
    string(REPLACE ";" "\n  " _list "${_left}")
    message(FATAL_ERROR "tests left these behind in their temporary folder:\n  ${_list}")
  endif ()
  message("the tests left nothing in ${DIR}")
else ()
  message(FATAL_ERROR "AFAMTestScratch: MODE must be setup or check")
endif ()
