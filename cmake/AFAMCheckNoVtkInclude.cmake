# SPDX-License-Identifier: BSD-3-Clause
# cmake -DAFAM_SOURCE_DIR=<root> -P AFAMCheckNoVtkInclude.cmake
# Fails when a file under Core/ or CudaKernels/ includes a VTK header: those layers must build on
# machines without VTK (DESIGN.md, "Layers").
if (NOT AFAM_SOURCE_DIR)
  message(FATAL_ERROR "pass -DAFAM_SOURCE_DIR=<source root>")
endif ()
set(_offenders "")
foreach (_dir Core CudaKernels)
  file(GLOB_RECURSE _files LIST_DIRECTORIES false
    "${AFAM_SOURCE_DIR}/${_dir}/*.h" "${AFAM_SOURCE_DIR}/${_dir}/*.hpp"
    "${AFAM_SOURCE_DIR}/${_dir}/*.hxx" "${AFAM_SOURCE_DIR}/${_dir}/*.cpp"
    "${AFAM_SOURCE_DIR}/${_dir}/*.cxx" "${AFAM_SOURCE_DIR}/${_dir}/*.cu"
    "${AFAM_SOURCE_DIR}/${_dir}/*.cuh" "${AFAM_SOURCE_DIR}/${_dir}/*.inl")
  foreach (_f IN LISTS _files)
    file(STRINGS "${_f}" _hits REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]vtk")
    if (_hits)
      list(APPEND _offenders "${_f}: ${_hits}")
    endif ()
  endforeach ()
endforeach ()
if (_offenders)
  string(REPLACE ";" "\n  " _msg "${_offenders}")
  message(FATAL_ERROR "VTK include in a VTK-free layer:\n  ${_msg}")
endif ()
message(STATUS "Core/ and CudaKernels/ include no VTK header")
