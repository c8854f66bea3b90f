# SPDX-License-Identifier: BSD-3-Clause
# Test of `afam compare-codecs` (run by ctest with -DAFAM=<exe> -DWORK=<dir>): on a generated
# Marschner-Lobb 65^3 float32 volume, the ZFP tuning lands at or below the target RMSE and within
# a factor 3 of it (ZFP's tolerances are powers of two, so one step is about a factor 2 in RMSE),
# ZFP's max error is within the tolerance it used, the Adaptive-FAM row carries the figures of
# `afam encode` + `afam verify --against`, the CSV has its columns and one row per (volume, bound,
# codec), the temporary folder is gone, and bad input fails with one line and exit status 1.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}/tmp")
include("${CMAKE_CURRENT_LIST_DIR}/cli_test_helpers.cmake")  # run_ok, run_fails

set(vol ml_65x65x65_float32.raw)
set(opts --levels 2 --blocks 4 --threads 2)
run_ok(out ${AFAM} compare-codecs --help)
if (NOT out MATCHES "usage: afam compare-codecs")
  message(FATAL_ERROR "compare-codecs --help: ${out}")
endif ()
run_ok(out ${AFAM} ml --size 65 ${vol})
run_ok(out ${AFAM} compare-codecs ${vol} --bounds 1e-2,1e-3 ${opts} --csv codecs.csv --work tmp)
if (NOT out MATCHES "adaptive-fam" OR NOT out MATCHES "zfp")
  message(FATAL_ERROR "compare-codecs table: ${out}")
endif ()
file(GLOB left "${WORK}/tmp/*")
if (left)
  message(FATAL_ERROR "the temporary folder was left behind: ${left}")
endif ()

file(STRINGS "${WORK}/codecs.csv" lines)
list(LENGTH lines n)
if (NOT n EQUAL 7)
  message(FATAL_ERROR "expected a header and 6 rows, got ${n} lines: ${lines}")
endif ()
list(GET lines 0 header)
set(expected_header "volume,dims,type,bound,codec,raw_bytes,compressed_bytes,ratio,rmse,rmse_relative,max_error,target_rmse,seconds,threads,setting")
if (NOT header STREQUAL expected_header)
  message(FATAL_ERROR "CSV header: ${header}")
endif ()
string(REPLACE "," ";" columns "${header}")

# Fails with `message` unless the awk expression `condition` holds (CMake has no floating point).
macro(expect_awk condition message)
  execute_process(COMMAND awk "BEGIN { exit !(${condition}) }" RESULT_VARIABLE awk_rc)
  if (NOT awk_rc EQUAL 0)
    message(FATAL_ERROR "${message}")
  endif ()
endmacro()

# row K as variables c_<column>
macro(read_row k)
  list(GET lines ${k} row)
  string(REPLACE "," ";" cells "${row}")
  list(LENGTH cells nc)
  if (NOT nc EQUAL 15)
    message(FATAL_ERROR "row ${k} has ${nc} cells: ${row}")
  endif ()
  foreach (i RANGE 14)
    list(GET columns ${i} name)
    list(GET cells ${i} c_${name})
  endforeach ()
endmacro()

set(k 1)
foreach (bound 0.01 0.001)
  # Adaptive-FAM: the same figures as encode + verify --against (the measure is shared).
  read_row(${k})
  if (NOT "${c_volume},${c_dims},${c_type},${c_bound},${c_codec},${c_raw_bytes}" STREQUAL
      "ml_65x65x65_float32,65x65x65,float32,${bound},adaptive-fam,1098500")
    message(FATAL_ERROR "row ${k}: ${row}")
  endif ()
  run_ok(enc ${AFAM} encode ${vol} ref_${bound}.afam --error-bound ${bound} --relative ${opts})
  file(SIZE "${WORK}/ref_${bound}.afam" afam_bytes)
  run_ok(ver ${AFAM} verify ref_${bound}.afam --against ${vol})
  if (NOT ver MATCHES "rmse=([0-9.eE+-]+) max_error=([0-9.eE+-]+)")
    message(FATAL_ERROR "verify: ${ver}")
  endif ()
  if (NOT c_compressed_bytes EQUAL afam_bytes OR NOT c_rmse STREQUAL CMAKE_MATCH_1 OR
      NOT c_max_error STREQUAL CMAKE_MATCH_2)
    message(FATAL_ERROR "adaptive-fam row ${row} differs from encode (${afam_bytes} bytes) + verify (${ver})")
  endif ()
  set(afam_rmse ${c_rmse})
  math(EXPR k "${k} + 1")

  # ZFP: at or below Adaptive-FAM's RMSE, within a factor 3, max error within the tolerance used.
  read_row(${k})
  if (NOT "${c_volume},${c_bound},${c_codec},${c_target_rmse}" STREQUAL "ml_65x65x65_float32,${bound},zfp,${afam_rmse}")
    message(FATAL_ERROR "row ${k}: ${row}")
  endif ()
  if (NOT c_setting MATCHES "tolerance=2\\^-?[0-9]+=([0-9.eE+-]+)")
    message(FATAL_ERROR "zfp setting: ${c_setting}")
  endif ()
  set(tolerance ${CMAKE_MATCH_1})
  if (c_rmse GREATER c_target_rmse OR c_max_error GREATER tolerance)
    message(FATAL_ERROR "zfp above its target or tolerance: ${row}")
  endif ()
  expect_awk("3 * ${c_rmse} > ${c_target_rmse}"
             "zfp rmse ${c_rmse} is more than a factor 3 below its target ${c_target_rmse}")
  message(STATUS "bound ${bound}: adaptive-fam rmse ${afam_rmse}, zfp rmse ${c_rmse} (tolerance ${tolerance})")
  set(zfp_rmse ${c_rmse})
  set(zfp_bytes ${c_compressed_bytes})
  math(EXPR k "${k} + 1")

  # ZFP with OpenMP on the encoder's 2 threads: the same tolerance, so the same decoded values.
  read_row(${k})
  if (NOT "${c_codec},${c_threads},${c_rmse}" STREQUAL "zfp-omp,2,${zfp_rmse}" OR
      NOT c_setting MATCHES "tolerance=2\\^-?[0-9]+=${tolerance} openmp_threads=2")
    message(FATAL_ERROR "zfp-omp row ${k}: ${row} (serial: rmse ${zfp_rmse}, tolerance ${tolerance})")
  endif ()
  expect_awk("${c_compressed_bytes} <= 1.01 * ${zfp_bytes}"
             "zfp-omp: ${c_compressed_bytes} bytes against ${zfp_bytes} serial")
  math(EXPR k "${k} + 1")
endforeach ()

# The tolerance search runs in slabs on every thread: on one thread (one slab) it finds the same
# tolerance at 1e-3 as on two (the last row pair above).
run_ok(out ${AFAM} compare-codecs ${vol} --bounds 1e-3 --levels 2 --blocks 4 --threads 1 --csv one.csv --work tmp --device cpu)
file(STRINGS "${WORK}/one.csv" one_lines)
list(GET one_lines 1 one_afam)
if (NOT one_afam MATCHES ",adaptive-fam,.*levels=2 blocks=4 degree=[0-9]+ device=cpu$")
  message(FATAL_ERROR "the adaptive-fam row does not say where it asked (--device cpu): ${one_afam}")
endif ()
list(GET one_lines 2 one_zfp)
if (NOT one_zfp MATCHES ",zfp,.*tolerance=2\\^(-?[0-9]+)=")
  message(FATAL_ERROR "zfp row tuned on one thread: ${one_zfp}")
endif ()
if (NOT c_setting MATCHES "tolerance=2\\^${CMAKE_MATCH_1}=")
  message(FATAL_ERROR "zfp tuned on one thread: ${one_zfp}; on two: ${c_setting}")
endif ()

# --max-error: both codecs held to the same largest error (bound x range), every sample within it.
run_ok(out ${AFAM} compare-codecs ${vol} --bounds 1e-2 ${opts} --max-error --csv point.csv --work tmp)
file(STRINGS "${WORK}/point.csv" lines)
foreach (k 1 2)
  read_row(${k})
  if (NOT c_target_rmse STREQUAL "${point_target}" AND k EQUAL 2)
    message(FATAL_ERROR "zfp's target ${c_target_rmse} is not adaptive-fam's bound ${point_target}")
  endif ()
  set(point_target ${c_target_rmse})
  expect_awk("${c_max_error} <= ${c_target_rmse} * (1 + 1e-6) && ${c_target_rmse} > 0"
             "--max-error: ${c_codec} is off by ${c_max_error}, above ${c_target_rmse}")
endforeach ()
run_ok(info ${AFAM} encode ${vol} point.afam --max-error 1e-2 --relative ${opts})
run_ok(info ${AFAM} info point.afam)
if (NOT info MATCHES "bound_kind=max_error")
  message(FATAL_ERROR "the pointwise file of compare-codecs' settings: ${info}")
endif ()

# Bad input: one line on stderr, exit status 1, no CSV.
file(WRITE "${WORK}/short_4x4x4_uint8.raw" "too short")
file(WRITE "${WORK}/notes.txt" "not a volume")
foreach (case
    "cannot open;missing_8x8x8_uint8.raw"
    "name_XxYxZ_type.raw;notes.txt"
    "name_XxYxZ_type.raw;ref_0.01.afam"
    "has 9 bytes;short_4x4x4_uint8.raw"
    "--bounds: every bound must be > 0;${vol};--bounds;0"
    "--bounds: every bound must be > 0;${vol};--bounds;1e-2,-1e-3"
    "--bounds: 'x' is not a number;${vol};--bounds;x"
    "no raw volume given"
    "levels and blocks per axis must be >= 1;${vol};--levels;-1"
    "nowhere/out.csv: its folder does not exist;${vol};--csv;nowhere/out.csv"
    "--zfp-target must be reached or bound;${vol};--zfp-target;half"
    "--device must be auto, gpu or cpu, not 'tpu';${vol};--device;tpu")
  list(GET case 0 pattern)
  list(REMOVE_AT case 0)
  run_fails("${pattern}" ${AFAM} compare-codecs --csv bad.csv --work tmp ${case})
  if (NOT RUN_FAILS_RC EQUAL 1)
    message(FATAL_ERROR "compare-codecs ${case}: exit status ${RUN_FAILS_RC}, expected 1")
  endif ()
  if (EXISTS "${WORK}/bad.csv")
    message(FATAL_ERROR "compare-codecs ${case} left bad.csv behind")
  endif ()
endforeach ()
file(GLOB left "${WORK}/tmp/*")
if (left)
  message(FATAL_ERROR "a failed compare-codecs left its temporary folder behind: ${left}")
endif ()
message(STATUS "compare-codecs test passed")
