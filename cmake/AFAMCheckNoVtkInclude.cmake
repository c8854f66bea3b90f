# SPDX-License-Identifier: BSD-3-Clause
# cmake -DAFAM_SOURCE_DIR=<root> [-DAFAM_CHECK=paraview] -P AFAMCheckNoVtkInclude.cmake
# Keeps the layers apart (DESIGN.md, "Layers"). By default it fails when a file under Core/ or
# CudaKernels/ includes a VTK header: those layers must build on machines without VTK. With
# AFAM_CHECK=paraview it fails when the VTK module (vtk.module: Readers/, Filters/, Mapper/) names
# a ParaView module or includes a ParaView header (vtkPV*, vtkSM*, vtkSI*): it must build against
# VTK alone; ParaView's side lives in Plugin/.
if (NOT AFAM_SOURCE_DIR)
  message(FATAL_ERROR "pass -DAFAM_SOURCE_DIR=<source root>")
endif ()
set(_offenders "")
if (AFAM_CHECK STREQUAL "paraview")
  set(_dirs Readers Filters Mapper)
  set(_include "vtk(PV|SM|SI)[A-Z]")
  set(_what "ParaView in the VTK-only module")
  set(_ok "the VTK module (Readers/, Filters/, Mapper/) depends on VTK alone")
  file(STRINGS "${AFAM_SOURCE_DIR}/vtk.module" _deps REGEX "ParaView::")
  if (_deps)
    list(APPEND _offenders "vtk.module: ${_deps}")
  endif ()
else ()
  set(_dirs Core CudaKernels)
  set(_include "vtk")
  set(_what "VTK include in a VTK-free layer")
  set(_ok "Core/ and CudaKernels/ include no VTK header")
endif ()
foreach (_dir IN LISTS _dirs)
  file(GLOB_RECURSE _files LIST_DIRECTORIES false
    "${AFAM_SOURCE_DIR}/${_dir}/*.h" "${AFAM_SOURCE_DIR}/${_dir}/*.hpp"
    "${AFAM_SOURCE_DIR}/${_dir}/*.hxx" "${AFAM_SOURCE_DIR}/${_dir}/*.cpp"
    "${AFAM_SOURCE_DIR}/${_dir}/*.cxx" "${AFAM_SOURCE_DIR}/${_dir}/*.cu"
    "${AFAM_SOURCE_DIR}/${_dir}/*.cuh" "${AFAM_SOURCE_DIR}/${_dir}/*.inl")
  foreach (_f IN LISTS _files)
    file(STRINGS "${_f}" _hits REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]${_include}")
    if (_hits)
      list(APPEND _offenders "${_f}: ${_hits}")
    endif ()
  endforeach ()
endforeach ()
if (_offenders)
  string(REPLACE ";" "\n  " _msg "${_offenders}")
  message(FATAL_ERROR "${_what}:\n  ${_msg}")
endif ()
message(STATUS "${_ok}")
