# SPDX-License-Identifier: BSD-3-Clause
# cmake -DAFAM_SOURCE_DIR=<root> -P AFAMCheckNoOutsidePath.cmake
# Fails when a source, script or CMake file of the repository names a folder beside the checkout
# (the sibling "shared" folder of a development machine): a clone must build, test, run its demo,
# benchmarks and evaluation from the repository alone. Test data live in Testing/Data, camera paths
# are generated (`afam trajectory`), recorded ones come only from $AFAM_TRAJECTORIES.
# It first checks itself on a planted offender, so that it cannot pass by matching nothing.
if (NOT AFAM_SOURCE_DIR)
  message(FATAL_ERROR "pass -DAFAM_SOURCE_DIR=<source root>")
endif ()
# The patterns, built from pieces so that this file does not name the folder itself: the parent
# folder followed by "shared" with any separator, and the same as the parts of a Python path join.
set(_up "[.][.]")
set(_patterns "${_up}[/\\\\]+shared" "\"${_up}\"[ \t]*,[ \t]*\"shared\"" "'${_up}'[ \t]*,[ \t]*'shared'")

# Files of the kinds that build, test or run something, under ROOT (not Testing/Data, not docs).
function(afam_checked_files root out)
  set(_globs "")
  foreach (_dir Apps Core CudaKernels Examples Filters Mapper Plugin Readers Testing cmake scripts .ci)
    foreach (_ext h hpp hxx cpp cxx cu cuh inl py sh cmake txt xml in json yml yaml)
      list(APPEND _globs "${root}/${_dir}/*.${_ext}")
    endforeach ()
    list(APPEND _globs "${root}/${_dir}/run")
  endforeach ()
  file(GLOB_RECURSE _files LIST_DIRECTORIES false ${_globs})
  list(FILTER _files EXCLUDE REGEX "^${root}/Testing/Data/")
  file(GLOB _top LIST_DIRECTORIES false "${root}/CMakeLists.txt" "${root}/vtk.module" "${root}/paraview.plugin")
  set(${out} ${_files} ${_top} PARENT_SCOPE)
endfunction()

function(afam_offenders root out)
  afam_checked_files("${root}" _files)
  set(_found "")
  foreach (_f IN LISTS _files)
    foreach (_p IN LISTS _patterns)
      file(STRINGS "${_f}" _hits REGEX "${_p}")
      foreach (_h IN LISTS _hits)
        file(RELATIVE_PATH _rel "${root}" "${_f}")
        string(STRIP "${_h}" _h)
        list(APPEND _found "${_rel}: ${_h}")
      endforeach ()
    endforeach ()
  endforeach ()
  list(LENGTH _files _n)
  set(${out} "${_found}" PARENT_SCOPE)
  set(${out}_checked ${_n} PARENT_SCOPE)
endfunction()

# Self-check: a planted script, CMake file and Python file must each be caught.
set(_dots "..")
string(RANDOM LENGTH 8 _tag)
set(_plant "${CMAKE_CURRENT_BINARY_DIR}/afam_outside_path_selfcheck_${_tag}")
file(REMOVE_RECURSE "${_plant}")
file(WRITE "${_plant}/scripts/x.sh" "data=\"$root/${_dots}//shared/data\"\n")
file(WRITE "${_plant}/Testing/CMakeLists.txt" "set(D \${CMAKE_SOURCE_DIR}/${_dots}/shared/data)\n")
file(WRITE "${_plant}/scripts/x.py" "T = os.path.join(ROOT, \"${_dots}\", \"shared\")\n")
file(WRITE "${_plant}/Core/ok.cpp" "// reads Testing/Data/volumes\n")
afam_offenders("${_plant}" _planted)
file(REMOVE_RECURSE "${_plant}")
list(LENGTH _planted _np)
if (NOT _np EQUAL 3)
  message(FATAL_ERROR "self-check: expected 3 planted offenders, found ${_np}: ${_planted}")
endif ()

afam_offenders("${AFAM_SOURCE_DIR}" _offenders)
if (_offenders)
  string(REPLACE ";" "\n  " _msg "${_offenders}")
  message(FATAL_ERROR "files that name a folder outside the repository:\n  ${_msg}")
endif ()
if (_offenders_checked LESS 100)
  message(FATAL_ERROR "only ${_offenders_checked} files checked under ${AFAM_SOURCE_DIR}: wrong root?")
endif ()
message(STATUS "${_offenders_checked} source, script and CMake files name no folder outside the repository")
