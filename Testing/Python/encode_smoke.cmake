# SPDX-License-Identifier: BSD-3-Clause
# Apps/pvbatch/afam_encode.py: a MetaImage and a gzip NRRD copy of a corpus volume, read by
# ParaView's own readers and encoded by the plugin, give the same micro-models as `afam encode`
# with the same options (`afam info` equal but for the file and scalar names, which come from the
# reader), also on 2 MPI ranks; a file ParaView cannot read fails with status 1 and no output.
# Run by ctest with -DAFAM= -DPLUGIN= -DPVBATCH= -DXVFB= -DTIMEOUT= -DSCRIPT= -DVOLUMES= -DWORK= [-DMPIRUN=]
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(bucky "${VOLUMES}/bucky_32x32x32_uint8.raw")
set(opts --levels 2 --blocks 4 --error-bound 1e-2 --relative --threads 2)
function(attach out header payload)
  file(WRITE "${WORK}/${out}.header" "${header}")
  execute_process(COMMAND ${CMAKE_COMMAND} -E cat "${WORK}/${out}.header" "${payload}" OUTPUT_FILE "${WORK}/${out}")
endfunction()
function(pvencode rc_var out_var)
  execute_process(COMMAND ${TIMEOUT} 300 ${XVFB} -a -s "-screen 0 640x480x24 -noreset" ${PVBATCH} ${SCRIPT}
                  --plugin ${PLUGIN} ${ARGN} WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(${rc_var} ${rc} PARENT_SCOPE)
  set(${out_var} "${out}${err}" PARENT_SCOPE)
endfunction()
# `afam info` from its third line on (the first two hold the file and scalar names).
function(models afam_file out_var)
  execute_process(COMMAND ${AFAM} info ${afam_file} WORKING_DIRECTORY "${WORK}" OUTPUT_VARIABLE out)
  string(REGEX MATCH "origin=.*" out "${out}")
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()

attach(bucky.mha "NDims = 3\nDimSize = 32 32 32\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" "${bucky}")
execute_process(COMMAND gzip -c -n "${bucky}" OUTPUT_FILE "${WORK}/bucky.raw.gz")
attach(bucky.nrrd "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 32 32 32\nencoding: gzip\n\n" "${WORK}/bucky.raw.gz")
execute_process(COMMAND ${AFAM} encode "${bucky}" cli.afam ${opts} --quiet WORKING_DIRECTORY "${WORK}")
models(cli.afam want)
if (NOT want MATCHES "level 1: blocks=4x4x4")
  message(FATAL_ERROR "afam info cli.afam: ${want}")
endif ()
foreach (input bucky.mha bucky.nrrd)
  pvencode(rc out ${input} ${input}.afam ${opts})
  if (NOT rc EQUAL 0 OR NOT out MATCHES "encode \\[#+\\] 100%" OR NOT out MATCHES "32x32x32\\) -> ${input}.afam")
    message(FATAL_ERROR "afam_encode.py ${input} (${rc}):\n${out}")
  endif ()
  models(${input}.afam got)
  if (NOT got STREQUAL want)
    message(FATAL_ERROR "afam_encode.py ${input}: models differ from afam encode's:\n${got}\nvs\n${want}")
  endif ()
endforeach ()
file(WRITE "${WORK}/notes.txt" "not a volume\n")
pvencode(rc out notes.txt bad.afam ${opts})
if (NOT rc EQUAL 1 OR NOT out MATCHES "afam_encode.py: error: .*notes.txt" OR EXISTS "${WORK}/bad.afam")
  message(FATAL_ERROR "afam_encode.py on a text file: expected status 1, one error line, no output (${rc}):\n${out}")
endif ()
# Under mpirun (2 ranks, each reading its piece of the MetaImage): afam encode's models again.
if (MPIRUN)
  execute_process(COMMAND ${TIMEOUT} 200 ${XVFB} -a -s "-screen 0 640x480x24 -noreset" ${MPIRUN}
                  --allow-run-as-root --oversubscribe -np 2 ${PVBATCH} ${SCRIPT} --plugin ${PLUGIN}
                  bucky.mha mpi.afam ${opts} WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if (NOT rc EQUAL 0 OR NOT "${out}${err}" MATCHES "ranks=2 ")
    message(FATAL_ERROR "afam_encode.py under mpirun (${rc}):\n${out}${err}")
  endif ()
  models(mpi.afam got)
  if (NOT got STREQUAL want)
    message(FATAL_ERROR "afam_encode.py on 2 ranks: models differ from afam encode's:\n${got}\nvs\n${want}")
  endif ()
endif ()
message(STATUS "afam_encode.py: MetaImage and gzip NRRD give afam encode's models")
