# SPDX-License-Identifier: BSD-3-Clause
# The VTK module AFAM::vtkAFAM (declared by the root vtk.module). Included from the staged module
# folder (see Plugin/CMakeLists.txt), so every path here is absolute.
get_filename_component(_afam_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)

set(_afam_classes
  Readers/vtkAFAMReader
  Readers/vtkAFAMWriter
  Filters/vtkAFAMEncoder
  Mapper/vtkAFAMVolumeMapper
  )

set(_afam_sources)
set(_afam_headers)
foreach (_class IN LISTS _afam_classes)
  list(APPEND _afam_sources "${_afam_root}/${_class}.cxx")
  list(APPEND _afam_headers "${_afam_root}/${_class}.h")
endforeach ()

# Private helpers: compiled in, neither wrapped nor installed.
set(_afam_private
  Readers/vtkAFAMModelTree
  Mapper/vtkAFAMCoreRenderer
  Mapper/vtkAFAMImageDraw
  Mapper/vtkAFAMTransferFunctionTable
  Mapper/vtkAFAMCudaGLBuffer
  Filters/vtkAFAMDistributedEncode
  Filters/vtkAFAMControllerTeam
  Filters/vtkAFAMMissingSamples
  )
# Encoding across MPI ranks needs VTK::ParallelMPI (an optional dependency in vtk.module); without
# it the encoder runs on one process and says so under several ranks.
if (TARGET VTK::ParallelMPI)
  list(APPEND _afam_private Filters/vtkAFAMPieceSource)
endif ()
set(_afam_private_headers)
foreach (_helper IN LISTS _afam_private)
  list(APPEND _afam_sources "${_afam_root}/${_helper}.cxx")
  list(APPEND _afam_private_headers "${_afam_root}/${_helper}.h")
endforeach ()

vtk_module_add_module(AFAM::vtkAFAM
  FORCE_STATIC
  SOURCES ${_afam_sources}
  HEADERS ${_afam_headers}
  PRIVATE_HEADERS ${_afam_private_headers})
vtk_module_include(AFAM::vtkAFAM
  PUBLIC
    "$<BUILD_INTERFACE:${_afam_root}/Readers>"
    "$<BUILD_INTERFACE:${_afam_root}/Filters>"
    "$<BUILD_INTERFACE:${_afam_root}/Mapper>")
if (TARGET VTK::ParallelMPI)
  vtk_module_definitions(AFAM::vtkAFAM PRIVATE AFAM_HAVE_MPI=1)
endif ()
# Core is VTK-free and static (PIC): linked into the module, nothing of it is exported.
vtk_module_link(AFAM::vtkAFAM PRIVATE afam_core)
# The GPU caster's factory (afam_gpu_caster, in every build): with nvcc (AFAM_ENABLE_CUDA) it is
# afam_cuda, static, PIC, linking cudart statically and bringing AFAM_HAVE_CUDA=1 (its PUBLIC
# definition) for the one file that talks to CUDA itself (Mapper/vtkAFAMCudaGLBuffer.cxx: CUDA's
# runtime and OpenGL-interop headers, through cudart's include directories); without nvcc, a stub
# that says so. The module includes only its plain C++ header (afam/cuda/render/make_gpu_caster.hpp).
vtk_module_link(AFAM::vtkAFAM PRIVATE afam_gpu_caster)
