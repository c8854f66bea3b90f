# AFAM_ENABLE_CUDA: on when nvcc is found; AFAM_ENABLE_PARAVIEW: on when ParaView 5.11 is found;
# AFAM_ENABLE_VTK: the VTK module and its image tests against a plain VTK (>= 9.1, no ParaView),
# on when ParaView is not wanted and VTK is found (VTK_DIR names a VTK's CMake folder).
include(CheckLanguage)
check_language(CUDA)
if (CMAKE_CUDA_COMPILER)
  set(_afam_cuda_default ON)
else ()
  set(_afam_cuda_default OFF)
endif ()
option(AFAM_ENABLE_CUDA "Build the CUDA decode-and-raycast kernels" ${_afam_cuda_default})

# AFAM_ENABLE_PARAVIEW=OFF, or AFAM_ENABLE_VTK=ON with ParaView left unset, does not even look for
# ParaView, so that nothing of it is imported into a plain-VTK build.
if (AFAM_ENABLE_PARAVIEW OR (NOT DEFINED AFAM_ENABLE_PARAVIEW AND NOT AFAM_ENABLE_VTK))
  find_package(ParaView 5.11 QUIET)
endif ()
if (ParaView_FOUND)
  set(_afam_pv_default ON)
else ()
  set(_afam_pv_default OFF)
endif ()
option(AFAM_ENABLE_PARAVIEW "Build the ParaView plugin and the VTK module" ${_afam_pv_default})

# What the plain-VTK build uses: the module's dependencies (vtk.module) and the image tests'.
set(AFAM_VTK_COMPONENTS
  CommonCore CommonDataModel CommonExecutionModel CommonMisc IOCore IOImage ParallelCore
  RenderingCore RenderingVolume RenderingOpenGL2 RenderingVolumeOpenGL2 opengl
  FiltersCore FiltersSources FiltersModeling ImagingCore InteractionStyle TestingRendering)
set(_afam_vtk_default OFF)
if (NOT AFAM_ENABLE_PARAVIEW AND (NOT DEFINED AFAM_ENABLE_VTK OR AFAM_ENABLE_VTK))
  find_package(VTK 9.1 QUIET COMPONENTS ${AFAM_VTK_COMPONENTS})
  if (VTK_FOUND)
    set(_afam_vtk_default ON)
  endif ()
endif ()
option(AFAM_ENABLE_VTK "Build the VTK module and its tests against VTK alone (no ParaView)"
  ${_afam_vtk_default})
if (AFAM_ENABLE_VTK AND AFAM_ENABLE_PARAVIEW)
  message(FATAL_ERROR "AFAM_ENABLE_VTK and AFAM_ENABLE_PARAVIEW are both ON: the ParaView build "
    "already builds the VTK module; turn one off")
endif ()
if (AFAM_ENABLE_VTK AND NOT VTK_FOUND)
  message(FATAL_ERROR "AFAM_ENABLE_VTK is ON but no VTK >= 9.1 with the components "
    "${AFAM_VTK_COMPONENTS} was found; set VTK_DIR to the folder holding vtk-config.cmake "
    "(with Debian's ParaView: /usr/lib/x86_64-linux-gnu/cmake/paraview-5.11/vtk)")
endif ()

if (AFAM_ENABLE_CUDA)
  if (NOT DEFINED CMAKE_CUDA_ARCHITECTURES)
    set(CMAKE_CUDA_ARCHITECTURES 90)  # H100/H200; CUDA 13 has nothing below sm_75
  endif ()
  enable_language(CUDA)
  find_package(CUDAToolkit REQUIRED)
endif ()
message(STATUS "Adaptive-FAM: CUDA ${AFAM_ENABLE_CUDA}, ParaView ${AFAM_ENABLE_PARAVIEW}, "
  "plain VTK ${AFAM_ENABLE_VTK} ${VTK_VERSION}")
