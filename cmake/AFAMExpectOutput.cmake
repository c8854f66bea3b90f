# SPDX-License-Identifier: BSD-3-Clause
# Runs a test's command and passes only when it exits 0 AND its output matches AFAM_EXPECT (a
# regular expression): ctest's PASS_REGULAR_EXPRESSION alone ignores the exit code, so a program
# that printed its success line and then crashed would pass.
#   cmake -DAFAM_EXPECT=<regex> -P AFAMExpectOutput.cmake <command> [args...]
set(_command)
set(_after_script FALSE)
set(_seen_p FALSE)
math(EXPR _last "${CMAKE_ARGC} - 1")
foreach (_i RANGE 1 ${_last})
  set(_arg "${CMAKE_ARGV${_i}}")
  if (_after_script)
    list(APPEND _command "${_arg}")
  elseif (_seen_p)
    set(_after_script TRUE)  # the script's own path
  elseif (_arg STREQUAL "-P")
    set(_seen_p TRUE)
  endif ()
endforeach ()
if (NOT _command OR NOT DEFINED AFAM_EXPECT)
  message(FATAL_ERROR "AFAMExpectOutput: usage: cmake -DAFAM_EXPECT=<regex> -P AFAMExpectOutput.cmake <command> [args...]")
endif ()
execute_process(COMMAND ${_command} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if (NOT _rc STREQUAL "0")
  message(FATAL_ERROR "AFAMExpectOutput: the command exited with ${_rc} (its output above)")
endif ()
if (NOT _out MATCHES "${AFAM_EXPECT}")
  message(FATAL_ERROR "AFAMExpectOutput: the output does not match '${AFAM_EXPECT}'")
endif ()
