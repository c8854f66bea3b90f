# SPDX-License-Identifier: BSD-3-Clause
# `afam enlarge`: a repository scan made large, in its own type, the same bytes on any number of
# threads, and encodable by its name; its error paths (run by ctest with -DAFAM=<exe> -DWORK=<dir>
# -DVOLUMES=<Testing/Data/volumes>).
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
include("${CMAKE_CURRENT_LIST_DIR}/cli_test_helpers.cmake")  # run_ok, run_fails

set(src "${VOLUMES}/HeadMRVolume_48x62x42_uint8.raw")
run_ok(out ${AFAM} enlarge ${src} big1_96x124x84_uint8.raw --dims 96,124,84 --threads 1)
if (NOT out MATCHES "noise sigma ([0-9.]+)")
  message(FATAL_ERROR "enlarge output: ${out}")
endif ()
file(SIZE "${WORK}/big1_96x124x84_uint8.raw" sz)
if (NOT sz EQUAL 999936)
  message(FATAL_ERROR "enlarge wrote ${sz} bytes, not 96*124*84 uint8")
endif ()
run_ok(out ${AFAM} enlarge ${src} big3_96x124x84_uint8.raw --dims 96,124,84 --threads 3)
file(SHA256 "${WORK}/big1_96x124x84_uint8.raw" h1)
file(SHA256 "${WORK}/big3_96x124x84_uint8.raw" h3)
if (NOT h1 STREQUAL h3)
  message(FATAL_ERROR "1 and 3 threads wrote different volumes")
endif ()
run_ok(out ${AFAM} enlarge ${src} seed2_96x124x84_uint8.raw --dims 96,124,84 --seed 2)
file(SHA256 "${WORK}/seed2_96x124x84_uint8.raw" h2)
if (h1 STREQUAL h2)
  message(FATAL_ERROR "--seed does not change the noise")
endif ()
# --detail: detail at every scale, the same bytes on any number of threads, refused when bad.
run_ok(out ${AFAM} enlarge ${src} det1_96x124x84_uint8.raw --dims 96,124,84 --detail 4 --threads 1)
if (NOT out MATCHES "detail sd 4 beta 0.5")
  message(FATAL_ERROR "enlarge --detail output: ${out}")
endif ()
run_ok(out ${AFAM} enlarge ${src} det3_96x124x84_uint8.raw --dims 96,124,84 --detail 4 --threads 3)
file(SHA256 "${WORK}/det1_96x124x84_uint8.raw" d1)
file(SHA256 "${WORK}/det3_96x124x84_uint8.raw" d3)
if (NOT d1 STREQUAL d3 OR d1 STREQUAL h1)
  message(FATAL_ERROR "--detail: 1 and 3 threads differ, or the detail changed nothing")
endif ()
run_ok(out ${AFAM} enlarge ${src} det0_96x124x84_uint8.raw --dims 96,124,84 --detail 0)
file(SHA256 "${WORK}/det0_96x124x84_uint8.raw" d0)
if (NOT d0 STREQUAL h1)
  message(FATAL_ERROR "--detail 0 changed the bytes")
endif ()
# --tissue-noise: noisier tissue, the air keeping --noise; the air's own value changes nothing.
run_ok(out ${AFAM} enlarge ${src} tis_96x124x84_uint8.raw --dims 96,124,84 --noise 2
       --tissue-noise 5)
if (NOT out MATCHES "noise sigma 2, in tissue 5")
  message(FATAL_ERROR "enlarge --tissue-noise output: ${out}")
endif ()
run_ok(out ${AFAM} enlarge ${src} tis2_96x124x84_uint8.raw --dims 96,124,84 --noise 2
       --tissue-noise 2)
run_ok(out ${AFAM} enlarge ${src} n2_96x124x84_uint8.raw --dims 96,124,84 --noise 2)
file(SHA256 "${WORK}/tis_96x124x84_uint8.raw" t5)
file(SHA256 "${WORK}/tis2_96x124x84_uint8.raw" t2)
file(SHA256 "${WORK}/n2_96x124x84_uint8.raw" n2)
if (NOT t2 STREQUAL n2 OR t5 STREQUAL n2)
  message(FATAL_ERROR "--tissue-noise equal to --noise changed the bytes, or 5 changed nothing")
endif ()

run_ok(out ${AFAM} encode big1_96x124x84_uint8.raw big.afam --error-bound 1e-2 --relative)
run_ok(out ${AFAM} verify big.afam --against big1_96x124x84_uint8.raw)

# Moving through it with no time for misses on slow storage (blocks still loading are drawn from
# resident coarser levels, Renderer.AFrameWaitsNoLongerThanItsMissBudget... counts them): the still
# frame after the path equals a frame rendered fresh (the CPU caster, 0/255).
run_ok(out ${AFAM} encode big1_96x124x84_uint8.raw levels.afam --error-bound 1e-2 --relative
       --levels 3 --blocks 8)
run_ok(out ${AFAM} trajectory dolly.dat --kind dolly)
set(view --size 64 --lod screen --cache-blocks 0 --threads 2)
run_ok(out ${AFAM} replay levels.afam --trajectory dolly.dat --frames 12 ${view} --storage-mbps 2
       --miss-budget-ms 0 --quiet --still-out still.png)
if (NOT out MATCHES "still_frame caching_ms=[0-9.]+ latency_ms=[0-9.]+ stand_ins=0")
  message(FATAL_ERROR "replay with a miss budget: ${out}")
endif ()
run_ok(out ${AFAM} render levels.afam --trajectory dolly.dat --view 11 ${view} --out fresh.png)
# The load threads' priority (nice steps below the frame's thread): 0..19, anything else refused.
run_fails("--load-nice must be in 0..19" ${AFAM} replay levels.afam --trajectory dolly.dat
          --frames 1 ${view} --load-nice 20)
run_ok(out ${AFAM} compare still.png fresh.png)
if (NOT out MATCHES "psnr=99")
  message(FATAL_ERROR "the still frame differs from a fresh render of the same view: ${out}")
endif ()

run_fails("--dims X,Y,Z is required" ${AFAM} enlarge ${src} x.raw)
run_fails("at least 2 samples" ${AFAM} enlarge ${src} x.raw --dims 1,8,8)
run_fails("noise must be finite" ${AFAM} enlarge ${src} x.raw --dims 8,8,8 --noise -1)
run_fails("the detail must be finite and >= 0" ${AFAM} enlarge ${src} x.raw --dims 8,8,8 --detail -1)
run_fails("the detail must be finite and >= 0" ${AFAM} enlarge ${src} x.raw --dims 8,8,8 --detail nan)
run_fails("the tissue noise must be finite and >= 0" ${AFAM} enlarge ${src} x.raw --dims 8,8,8
          --tissue-noise -2)
run_fails("beta must be in" ${AFAM} enlarge ${src} x.raw --dims 8,8,8 --detail 1 --detail-beta 9)
run_fails("give --dims" ${AFAM} enlarge ${WORK}/big.afam x.raw --dims 8,8,8)
if (EXISTS "${WORK}/x.raw" OR EXISTS "${WORK}/x.raw.tmp")
  message(FATAL_ERROR "a failed enlarge left a file")
endif ()
