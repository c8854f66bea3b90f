# SPDX-License-Identifier: BSD-3-Clause
# Missing samples from the command line: `afam mask` makes a CT's field of view with a fill value;
# `afam encode --missing-value` keeps the bound on the valid samples and the mask exactly (`afam
# verify`), `afam info` says what marked them; a run takes the value at every step and an append
# takes the run's; `afam render --nan-color` draws them; bad fill values and volumes without a
# valid sample are refused by name (run by ctest with -DAFAM=<exe> -DWORK=<dir>
# -DVOLUMES=<Testing/Data/volumes>).
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
include("${CMAKE_CURRENT_LIST_DIR}/cli_test_helpers.cmake")  # run_ok, run_fails

set(src "${VOLUMES}/headsq_quarter_64x64x93_int16.raw")
run_ok(out ${AFAM} mask ${src} fov_64x64x93_float32.raw --shape fov --fill -1024)
if (NOT out MATCHES "missing=93000 of 380928 samples")
  message(FATAL_ERROR "afam mask --shape fov: ${out}")
endif ()
run_ok(out ${AFAM} encode fov_64x64x93_float32.raw fov.afam --error-bound 1e-2 --relative
       --missing-value -1024 --levels 2 --blocks 3)
run_ok(out ${AFAM} info fov.afam)
if (NOT out MATCHES "version=3" OR NOT out MATCHES "missing=value\\(-1024\\)"
    OR NOT out MATCHES "masked=[1-9]")
  message(FATAL_ERROR "afam info of a file with missing samples: ${out}")
endif ()
foreach (level 0 1)
  run_ok(out ${AFAM} verify fov.afam --against fov_64x64x93_float32.raw --level ${level})
  if (NOT out MATCHES "missing=[1-9][0-9]* mask_mismatches=0")
    message(FATAL_ERROR "afam verify level ${level}: ${out}")
  endif ()
endforeach ()
# Drawn: by default missing samples are not drawn (a NaN opacity of 0 draws the same image);
# --nan-color R,G,B,A draws them, over the field of view's corners.
run_ok(out ${AFAM} trajectory orbit.dat --kind orbit --views 36 --distance 1.25)
run_ok(out ${AFAM} render fov.afam --trajectory orbit.dat --view 9 --size 64 --out plain.png)
run_ok(out ${AFAM} render fov.afam --trajectory orbit.dat --view 9 --size 64 --out none.png
       --nan-color 1,0,0,0)
run_ok(out ${AFAM} render fov.afam --trajectory orbit.dat --view 9 --size 64 --out red.png
       --nan-color 1,0,0,1)
run_ok(out ${AFAM} compare plain.png none.png)
if (NOT out MATCHES "mse=0")
  message(FATAL_ERROR "a NaN opacity of 0 changed the image: ${out}")
endif ()
run_ok(out ${AFAM} compare plain.png red.png)
if (NOT out MATCHES "psnr=([0-9.]+)" OR CMAKE_MATCH_1 GREATER 20)
  message(FATAL_ERROR "--nan-color did not draw the missing samples: ${out}")
endif ()
run_fails("give R,G,B,A" ${AFAM} render fov.afam --trajectory orbit.dat --out bad.png
          --nan-color 1,0,0)
run_fails("2 is outside \\[0, 1\\]" ${AFAM} render fov.afam --trajectory orbit.dat --out bad.png
          --nan-color 1,0,0,2)
# A run of two steps with the fill value, then an append of a third.
run_ok(out ${AFAM} mask ${src} ball_64x64x93_float32.raw --shape ball --fill -1024)
run_ok(out ${AFAM} encode fov_64x64x93_float32.raw ball_64x64x93_float32.raw run.afam
       --error-bound 1e-2 --relative --missing-value -1024 --levels 2 --blocks 3)
run_ok(out ${AFAM} encode --append ball_64x64x93_float32.raw run.afam)
run_ok(out ${AFAM} verify run.afam --against fov_64x64x93_float32.raw ball_64x64x93_float32.raw
       ball_64x64x93_float32.raw)
string(REGEX MATCHALL "mask_mismatches=0" ok "${out}")
list(LENGTH ok steps)
if (NOT steps EQUAL 3)
  message(FATAL_ERROR "afam verify of a run with missing samples: ${out}")
endif ()
run_fails("the run has the missing value" ${AFAM} encode --append ball_64x64x93_float32.raw
          run.afam --missing-value 7)
# Bad input, named.
run_fails("missing value nan is NaN" ${AFAM} encode ${src} bad.afam --missing-value nan)
run_fails("outside the range" ${AFAM} encode ${src} bad.afam --missing-value 40000)
run_fails("not an integer" ${AFAM} encode ${src} bad.afam --missing-value 1.5)
run_fails("mode ds cannot store" ${AFAM} encode fov_64x64x93_float32.raw bad.afam
          --missing-value -1024 --mode ds)
if (EXISTS "${WORK}/bad.afam")
  message(FATAL_ERROR "a refused encode left bad.afam")
endif ()
