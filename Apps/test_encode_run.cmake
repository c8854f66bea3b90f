# SPDX-License-Identifier: BSD-3-Clause
# `afam encode IN0 IN1 ... OUT`: a run of steps in one file (format version 3) that `afam info`
# lists and `afam decode --step` decodes; a step identical to the one before refers to it and
# decodes to the same bytes; bad runs are refused and leave nothing (run by ctest with
# -DAFAM=<exe> -DWORK=<dir> -DVOLUMES=<Testing/Data/volumes>).
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
include("${CMAKE_CURRENT_LIST_DIR}/cli_test_helpers.cmake")  # run_ok, run_fails

set(src "${VOLUMES}/HeadMRVolume_48x62x42_uint8.raw")
run_ok(out ${AFAM} enlarge ${src} a_64x80x56_uint8.raw --dims 64,80,56 --seed 1)
run_ok(out ${AFAM} enlarge ${src} b_64x80x56_uint8.raw --dims 64,80,56 --seed 2)
# Coded to the whole bound (no headroom: ResidualCoding.ARunLeavesHeadroom... looks at it), so
# that the step appended below, a scan of other noise, needs a residual.
run_ok(out ${AFAM} encode a_64x80x56_uint8.raw a_64x80x56_uint8.raw b_64x80x56_uint8.raw run.afam
       --error-bound 1e-2 --relative --times 0,0.5,1.5 --key-interval 4 --coded-share 1)
if (NOT out MATCHES "step=1 time=0.5 input=a_64x80x56_uint8.raw blocks=([0-9]+) references=([0-9]+) residuals=0 decoded_before=([0-9]+) payload_bytes=0 ")
  message(FATAL_ERROR "the repeated step was not stored as references: ${out}")
endif ()
if (NOT CMAKE_MATCH_1 EQUAL CMAKE_MATCH_2 OR NOT CMAKE_MATCH_1 EQUAL CMAKE_MATCH_3)
  message(FATAL_ERROR "step 1: ${CMAKE_MATCH_2} references of ${CMAKE_MATCH_1} blocks, "
                      "${CMAKE_MATCH_3} models of the step before decoded")
endif ()
if (NOT out MATCHES "steps=3 key_interval=4 bound=2.55 \\(relative to the run\\)")
  message(FATAL_ERROR "run summary: ${out}")
endif ()
run_ok(out ${AFAM} info run.afam)
if (NOT out MATCHES "version=3" OR NOT out MATCHES "steps=3 key_interval=4"
    OR NOT out MATCHES "step=1 time=0.5 references=[0-9]+ residuals=0 of [0-9]+ longest_chain=[0-9]+ payload_bytes=0\n"
    OR NOT out MATCHES "step=2 time=1.5 references=0 [^\n]* payload_bytes=[1-9]")
  message(FATAL_ERROR "afam info of a run: ${out}")
endif ()
run_ok(out ${AFAM} decode run.afam --step 0 s0.raw)
run_ok(out ${AFAM} decode run.afam --step 1 s1.raw)
run_ok(out ${AFAM} decode run.afam --step 2 s2.raw)
file(SHA256 "${WORK}/s0.raw" h0)
file(SHA256 "${WORK}/s1.raw" h1)
file(SHA256 "${WORK}/s2.raw" h2)
if (NOT h0 STREQUAL h1 OR h0 STREQUAL h2)
  message(FATAL_ERROR "steps 0 and 1 (the same input) should decode alike, step 2 not")
endif ()
run_ok(out ${AFAM} verify run.afam --against a_64x80x56_uint8.raw a_64x80x56_uint8.raw
       b_64x80x56_uint8.raw)
if (NOT out MATCHES "step=0 time=0 damaged=0 level=[0-9]+ rmse=[0-9.e-]+ max_error=[0-9.e-]+\n"
    OR NOT out MATCHES "step=2 time=1.5 damaged=0 level=")
  message(FATAL_ERROR "afam verify of a run: ${out}")
endif ()
# A step extracted as a file of its own: version 2, and it decodes to the step's bytes.
run_ok(out ${AFAM} extract run.afam --step 2 step2.afam)
if (NOT out MATCHES "models=[0-9]+ copied=[0-9]+ resolved=[0-9]+")
  message(FATAL_ERROR "afam extract: ${out}")
endif ()
run_ok(out ${AFAM} info step2.afam)
if (NOT out MATCHES "version=2" OR out MATCHES "steps=")
  message(FATAL_ERROR "an extracted step is not a one-step file: ${out}")
endif ()
run_ok(out ${AFAM} decode step2.afam e2.raw)
file(SHA256 "${WORK}/e2.raw" e2)
if (NOT e2 STREQUAL h2)
  message(FATAL_ERROR "the extracted step decodes otherwise than step 2 of the run")
endif ()
run_fails("--step K is required" ${AFAM} extract run.afam x.afam)
run_fails("1 of 3 steps damaged or above the bound" ${AFAM} verify run.afam --against
          a_64x80x56_uint8.raw b_64x80x56_uint8.raw b_64x80x56_uint8.raw)
run_fails("2 inputs for a run of 3 steps" ${AFAM} verify run.afam --against a_64x80x56_uint8.raw
          b_64x80x56_uint8.raw)

# Appending a step in place, as a running simulation would.
# (b again after b: every block refers to the step before)
run_ok(out ${AFAM} encode --append b_64x80x56_uint8.raw run.afam --times 4)
if (NOT out MATCHES "appended b_64x80x56_uint8.raw -> run.afam: blocks=([0-9]+) references=([0-9]+) residuals=0 payload_bytes=0 ")
  message(FATAL_ERROR "append: ${out}")
endif ()
if (NOT CMAKE_MATCH_1 EQUAL CMAKE_MATCH_2)
  message(FATAL_ERROR "appending the last step again: ${CMAKE_MATCH_2} references of ${CMAKE_MATCH_1}")
endif ()
run_ok(out ${AFAM} info run.afam)
if (NOT out MATCHES "steps=4 key_interval=4" OR NOT out MATCHES "step=3 time=4 references=")
  message(FATAL_ERROR "afam info after the append: ${out}")
endif ()
run_ok(out ${AFAM} verify run.afam --against a_64x80x56_uint8.raw a_64x80x56_uint8.raw
       b_64x80x56_uint8.raw b_64x80x56_uint8.raw)
run_ok(out ${AFAM} encode --append a_64x80x56_uint8.raw run.afam)
if (NOT out MATCHES "references=0 residuals=[0-9]+ payload_bytes=[1-9]")
  message(FATAL_ERROR "appending another step: ${out}")
endif ()
run_ok(out ${AFAM} info run.afam)
if (NOT out MATCHES "step=4 time=5 references=")
  message(FATAL_ERROR "the default time of an appended step: ${out}")
endif ()
run_fails("time 3.000000 does not follow 5.000000" ${AFAM} encode --append a_64x80x56_uint8.raw
          run.afam --times 3)
run_fails("dims differ from the run's" ${AFAM} encode --append ${src} run.afam)

# A step of a run rendered: step 1 (a again, references) as step 0, step 2 (b) not.
run_ok(out ${AFAM} trajectory orbit.dat --kind orbit)
foreach (k 0 1 2)
  run_ok(out ${AFAM} render run.afam --trajectory orbit.dat --view 3 --size 48 --step ${k}
         --out step${k}.png)
endforeach ()
run_ok(out ${AFAM} compare step0.png step1.png)
if (NOT out MATCHES "psnr=99")
  message(FATAL_ERROR "step 1 (references to step 0) renders differently: ${out}")
endif ()
run_ok(out ${AFAM} compare step0.png step2.png)
if (out MATCHES "psnr=99")
  message(FATAL_ERROR "steps 0 and 2 (different inputs) render alike")
endif ()
run_ok(out ${AFAM} replay run.afam --trajectory orbit.dat --frames 3 --size 32 --step 2 --quiet)
run_fails("step 9 of a run of" ${AFAM} render run.afam --trajectory orbit.dat --step 9 --out x.png)
# Playback with a still camera, twice over the run: the second pass reads nothing (the cache
# keeps every step's models), and a step that refers to the one before misses nothing.
run_ok(out ${AFAM} replay run.afam --trajectory orbit.dat --steps 0:4 --view 3 --frames 10
       --size 32 --cache-blocks 0)
if (NOT out MATCHES "pov=4 step=4 " OR NOT out MATCHES "pov=9 step=4 "
    OR NOT out MATCHES "pov=1 step=1 [^\n]* misses=0 ")
  message(FATAL_ERROR "playback: ${out}")
endif ()
foreach (pov 5 6 7 8 9)
  if (NOT out MATCHES "pov=${pov} step=[0-4] [^\n]* misses=0 bytes_read=0 ")
    message(FATAL_ERROR "the second pass of the playback read again (view ${pov}): ${out}")
  endif ()
endforeach ()
run_ok(out ${AFAM} replay run.afam --trajectory orbit.dat --steps 4:0 --view 3 --frames 5
       --size 32 --quiet)
run_fails("--steps 0:9 outside the 5 steps" ${AFAM} replay run.afam --trajectory orbit.dat
          --steps 0:9)

# One input keeps today's file (version 2), byte for byte what a single encode writes.
run_ok(out ${AFAM} encode a_64x80x56_uint8.raw one.afam --error-bound 1e-2 --relative)
run_ok(out ${AFAM} info one.afam)
if (NOT out MATCHES "version=2" OR out MATCHES "steps=")
  message(FATAL_ERROR "one input: ${out}")
endif ()

run_fails("step 5 of a run of 5 steps" ${AFAM} decode run.afam --step 5 x.raw)
run_fails("step 1 of a file of one step" ${AFAM} decode one.afam --step 1 x.raw)
run_fails("step 7 of a run of 5 steps" ${AFAM} extract run.afam --step 7 x.afam)
if (EXISTS "${WORK}/x.afam")
  message(FATAL_ERROR "a refused extract left a file")
endif ()
run_fails("appending needs a run" ${AFAM} encode --append b_64x80x56_uint8.raw one.afam)
run_fails("time values must increase: step 1" ${AFAM} encode a_64x80x56_uint8.raw
          b_64x80x56_uint8.raw bad.afam --times 1,1)
run_fails("2 time values for 3 steps" ${AFAM} encode a_64x80x56_uint8.raw b_64x80x56_uint8.raw
          a_64x80x56_uint8.raw bad.afam --times 0,1)
run_fails("step 1 \\(HeadMRVolume\\): dims 48x62x42 differ from the first step's 64x80x56"
          ${AFAM} encode a_64x80x56_uint8.raw ${src} bad.afam)
run_ok(out ${AFAM} decode one.afam float_64x80x56_float32.raw)
run_fails("step 1 \\(float_64x80x56_float32.raw\\): sample type float32 differs from the first step's uint8"
          ${AFAM} encode a_64x80x56_uint8.raw float_64x80x56_float32.raw bad.afam)
run_fails("samples of 4 bytes differ from the run's 1" ${AFAM} encode --append
          float_64x80x56_float32.raw run.afam)
run_fails("need several inputs" ${AFAM} encode a_64x80x56_uint8.raw bad.afam --times 0)
run_fails("cannot open" ${AFAM} encode a_64x80x56_uint8.raw missing_64x80x56_uint8.raw bad.afam)
file(GLOB left "${WORK}/bad.afam*")
if (left)
  message(FATAL_ERROR "a refused run left ${left}")
endif ()

# afam simulate: a run of a real simulation, the same bytes for the same arguments, encodable as
# one run.
run_ok(out ${AFAM} simulate gs --dims 12,10,8 --steps 3 --every 5 --warmup 20 --seeds 2)
run_ok(out ${AFAM} simulate again --dims 12,10,8 --steps 3 --every 5 --warmup 20 --seeds 2)
foreach (k 0000 0001 0002)
  file(SHA256 "${WORK}/gs_${k}_12x10x8_float32.raw" a)
  file(SHA256 "${WORK}/again_${k}_12x10x8_float32.raw" b)
  if (NOT a STREQUAL b)
    message(FATAL_ERROR "afam simulate is not deterministic (step ${k})")
  endif ()
endforeach ()
file(SHA256 "${WORK}/gs_0000_12x10x8_float32.raw" a)
file(SHA256 "${WORK}/gs_0002_12x10x8_float32.raw" b)
if (a STREQUAL b)
  message(FATAL_ERROR "afam simulate: the saved steps do not evolve")
endif ()
run_ok(out ${AFAM} encode gs_0000_12x10x8_float32.raw gs_0001_12x10x8_float32.raw
       gs_0002_12x10x8_float32.raw gs.afam --error-bound 1e-2 --relative)
run_fails("--dims and --steps are required" ${AFAM} simulate x)
run_fails("dims must be >= 3 per axis" ${AFAM} simulate x --dims 2,8,8 --steps 1)
