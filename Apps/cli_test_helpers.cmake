# SPDX-License-Identifier: BSD-3-Clause
# Helpers of the command-line tests (cmake -P scripts); commands run in ${WORK}.

function(run_ok out_var)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if (NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\nstdout: ${out}\nstderr: ${err}")
  endif ()
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()

# An error: non-zero exit and exactly one non-empty line on stderr naming the problem; the exit
# status is left in RUN_FAILS_RC.
function(run_fails pattern)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if (rc EQUAL 0)
    message(FATAL_ERROR "expected a failure: ${ARGN}")
  endif ()
  string(STRIP "${err}" e)
  string(FIND "${e}" "\n" nl)
  if (NOT nl EQUAL -1 OR e STREQUAL "")
    message(FATAL_ERROR "expected one line on stderr for ${ARGN}, got: '${err}'")
  endif ()
  if (NOT e MATCHES "${pattern}")
    message(FATAL_ERROR "stderr of ${ARGN} does not match '${pattern}': ${e}")
  endif ()
  set(RUN_FAILS_RC "${rc}" PARENT_SCOPE)
endfunction()
