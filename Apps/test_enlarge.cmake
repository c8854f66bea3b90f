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
run_ok(out ${AFAM} encode big1_96x124x84_uint8.raw big.afam --error-bound 1e-2 --relative)
run_ok(out ${AFAM} verify big.afam --against big1_96x124x84_uint8.raw)

run_fails("--dims X,Y,Z is required" ${AFAM} enlarge ${src} x.raw)
run_fails("at least 2 samples" ${AFAM} enlarge ${src} x.raw --dims 1,8,8)
run_fails("noise must be finite" ${AFAM} enlarge ${src} x.raw --dims 8,8,8 --noise -1)
run_fails("give --dims" ${AFAM} enlarge ${WORK}/big.afam x.raw --dims 8,8,8)
if (EXISTS "${WORK}/x.raw" OR EXISTS "${WORK}/x.raw.tmp")
  message(FATAL_ERROR "a failed enlarge left a file")
endif ()
