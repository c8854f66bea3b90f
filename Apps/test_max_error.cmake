# SPDX-License-Identifier: BSD-3-Clause
# `afam encode --max-error E`: a pointwise bound. The file is version 3 (one step) and says what it
# keeps (`afam info`: bound_kind=max_error); `afam verify --against` finds every sample within E
# (and exits 1 against another volume); the same volume at an RMSE bound of E has samples further
# off; bad options are refused (run by ctest with -DAFAM=<exe> -DWORK=<dir>
# -DVOLUMES=<Testing/Data/volumes>).
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
include("${CMAKE_CURRENT_LIST_DIR}/cli_test_helpers.cmake")  # run_ok, run_fails

set(mri "${VOLUMES}/HeadMRVolume_48x62x42_uint8.raw")
run_ok(out ${AFAM} enlarge ${mri} scan_64x80x56_uint8.raw --dims 64,80,56 --seed 3)
run_ok(out ${AFAM} encode scan_64x80x56_uint8.raw point.afam --max-error 1e-2 --relative)
if (NOT out MATCHES "bound=2.55 \\(relative, pointwise\\)")
  message(FATAL_ERROR "afam encode --max-error: ${out}")
endif ()
run_ok(out ${AFAM} info point.afam)
if (NOT out MATCHES "version=3" OR NOT out MATCHES "bound_kind=max_error")
  message(FATAL_ERROR "afam info of a pointwise file: ${out}")
endif ()
run_ok(out ${AFAM} verify point.afam --against scan_64x80x56_uint8.raw)
if (NOT out MATCHES "max_error=([0-9.e+-]+)")
  message(FATAL_ERROR "afam verify: ${out}")
endif ()
if (CMAKE_MATCH_1 GREATER 2.55001)
  message(FATAL_ERROR "a sample is off by ${CMAKE_MATCH_1}, over the bound 2.55")
endif ()
# Every level, against its own filtered samples.
run_ok(out ${AFAM} verify point.afam --against scan_64x80x56_uint8.raw --level 0)
# The RMSE bound of the same size lets samples further off.
run_ok(out ${AFAM} encode scan_64x80x56_uint8.raw rmse.afam --error-bound 1e-2 --relative)
run_ok(out ${AFAM} info rmse.afam)
if (NOT out MATCHES "version=2" OR NOT out MATCHES "bound_kind=rmse")
  message(FATAL_ERROR "afam info of an RMSE file: ${out}")
endif ()
run_ok(out ${AFAM} verify rmse.afam --against scan_64x80x56_uint8.raw)
if (NOT out MATCHES "max_error=([0-9.e+-]+)" OR NOT CMAKE_MATCH_1 GREATER 2.55)
  message(FATAL_ERROR "the RMSE file keeps every sample within 2.55 too: the test means nothing")
endif ()
# Against another scan: above the pointwise bound, exit status 1.
run_ok(out ${AFAM} enlarge ${mri} other_64x80x56_uint8.raw --dims 64,80,56 --seed 4 --noise 12)
run_fails("above the file's pointwise bound" ${AFAM} verify point.afam --against
          other_64x80x56_uint8.raw)
run_fails("--error-bound \\(an RMSE\\) or --max-error" ${AFAM} encode scan_64x80x56_uint8.raw x.afam
          --error-bound 1e-2 --max-error 1e-2)
run_fails("needs a bounded mode" ${AFAM} encode scan_64x80x56_uint8.raw x.afam --max-error 1e-2
          --mode fixed)
if (EXISTS "${WORK}/x.afam")
  message(FATAL_ERROR "a refused encode left a file")
endif ()
