# SPDX-License-Identifier: BSD-3-Clause
# Smoke test of the README main job's pvbatch side (Apps/pvbatch/afam_demo.py) on a tiny volume:
# ML 33^3 encoded adaptive, one view of a generated exploration path at 40 x 40, rendered through
# the plugin, by `afam render` and by ParaView's Volume representation. Checks the report and that
# the plugin's image equals afam render's (one renderer, two front ends: PSNR >= 40 dB between
# them). Then the real-volume part (afam_demo_real.py) on bucky 32^3: sizes, data error and the
# plugin against ParaView's Volume representation of the raw file.
# Run by ctest with -DAFAM= -DPLUGIN= -DPVBATCH= -DXVFB= -DTIMEOUT= -DSCRIPT= -DREAL_SCRIPT=
# -DVOLUMES= -DWORK=
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
function(run_ok)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if (NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}")
  endif ()
  message(STATUS "${out}")
endfunction()
run_ok(${AFAM} trajectory walk.dat --kind walk --views 400 --seed 1)
set(TRAJ "${WORK}/walk.dat")
run_ok(${AFAM} ml --size 33 ml.raw)
run_ok(${AFAM} encode ml.raw ml.afam --dims 33,33,33 --levels 2 --blocks 4 --error-bound 1e-3 --quiet)
run_ok(${TIMEOUT} 600 ${XVFB} -a -s "-screen 0 1280x1024x24 -noreset" ${PVBATCH} ${SCRIPT}
       --plugin ${PLUGIN} --afam ${AFAM} --trajectory ${TRAJ} --out ${WORK}/out --method adaptive=ml.afam
       --raw ml.raw --views 200 --size 40 --repeats 1 --sample-distance 0.02 --threads 2)
file(STRINGS "${WORK}/out/report.csv" lines)
list(LENGTH lines n)
if (NOT n EQUAL 4)
  message(FATAL_ERROR "report.csv: expected a header and 3 rows, got ${n}: ${lines}")
endif ()
foreach (line IN LISTS lines)
  if (line MATCHES "^plugin,adaptive,200,[^,]*,[^,]*,1,([0-9.]+),[^,]*,([0-9.]+),")
    if (CMAKE_MATCH_2 LESS 40)
      message(FATAL_ERROR "plugin image differs from afam render's: ${CMAKE_MATCH_2} dB")
    endif ()
    set(found_plugin 1)
  endif ()
  if (line MATCHES "^ParaView Volume,raw,200,")
    set(found_volume 1)
  endif ()
endforeach ()
if (NOT found_plugin OR NOT found_volume)
  message(FATAL_ERROR "report.csv lacks the plugin or ParaView Volume row: ${lines}")
endif ()
foreach (png afam_adaptive_200 plugin_adaptive_200 paraview_raw_200 gt_200)
  if (NOT EXISTS "${WORK}/out/${png}.png")
    message(FATAL_ERROR "missing ${png}.png")
  endif ()
endforeach ()

# The real-volume part: bucky 32^3 (uint8), one view of an orbit that sees the whole volume.
set(bucky "${VOLUMES}/bucky_32x32x32_uint8.raw")
run_ok(${AFAM} encode ${bucky} bucky.afam --levels 2 --blocks 4 --error-bound 1e-2 --relative --quiet)
run_ok(${AFAM} trajectory orbit.dat --kind orbit --views 4 --distance 9 --theta 70)
execute_process(COMMAND ${TIMEOUT} 600 ${XVFB} -a -s "-screen 0 1280x1024x24 -noreset" ${PVBATCH} ${REAL_SCRIPT}
    --plugin ${PLUGIN} --afam ${AFAM} --file bucky.afam --raw ${bucky} --trajectory orbit.dat
    --out ${WORK}/out --views 1 --size 40 --repeats 1 --sample-distance 0.02 --threads 2
  WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if (NOT rc EQUAL 0 OR NOT out MATCHES "raw 32768 bytes, .afam ([0-9]+) bytes .*rmse ([0-9.e+-]+)")
  message(FATAL_ERROR "afam_demo_real.py failed (${rc}):\n${out}")
endif ()
message(STATUS "${out}")
file(STRINGS "${WORK}/out/report_real.csv" lines)
list(GET lines 1 row)
if (NOT row MATCHES "^bucky_32x32x32_uint8.raw,1,32768,[0-9]+,[0-9.]+,[0-9.e+-]+,[0-9.e+-]+,[0-9.]+,[0-9.]+,([0-9.]+),([0-9.]+)$")
  message(FATAL_ERROR "report_real.csv row: ${row}")
endif ()
# Two renderers of the same data with one transfer function: the images must agree broadly.
if (CMAKE_MATCH_1 LESS 20)
  message(FATAL_ERROR "plugin image far from ParaView's Volume representation: ${CMAKE_MATCH_1} dB")
endif ()
foreach (png real_plugin_1 real_paraview_1)
  if (NOT EXISTS "${WORK}/out/${png}.png")
    message(FATAL_ERROR "missing ${png}.png")
  endif ()
endforeach ()
