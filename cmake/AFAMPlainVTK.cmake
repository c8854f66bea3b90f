# SPDX-License-Identifier: BSD-3-Clause
# The VTK module AFAM::vtkAFAM built against VTK alone (AFAM_ENABLE_VTK): the module the ParaView
# plugin builds, from the same root vtk.module staged the same way (Plugin/CMakeLists.txt says why
# the root folder itself cannot be the module's folder), with no ParaView target anywhere.
include("${CMAKE_CURRENT_LIST_DIR}/AFAMStageDescriptor.cmake")

if (TARGET ParaView::RemotingCore OR TARGET ParaView::VTKExtensionsCore)
  message(FATAL_ERROR "plain VTK: ParaView's targets were imported; configure with "
    "-DAFAM_ENABLE_PARAVIEW=OFF and a VTK_DIR that is not ParaView's own package")
endif ()
if (NOT TARGET afam_core)
  message(FATAL_ERROR "plain VTK: the afam_core target (Core/) must be defined first")
endif ()

set(_afam_stage "${CMAKE_BINARY_DIR}/afam_stage")
afam_stage_descriptor("${CMAKE_CURRENT_LIST_DIR}/../vtk.module" "${_afam_stage}/module"
  "${CMAKE_CURRENT_LIST_DIR}/AFAMVTKModule.cmake")

vtk_module_scan(
  MODULE_FILES     "${_afam_stage}/module/vtk.module"
  REQUEST_MODULES  AFAM::vtkAFAM
  PROVIDES_MODULES _afam_vtk_modules
  ENABLE_TESTS     OFF)
include(GNUInstallDirs)
vtk_module_build(
  MODULES           ${_afam_vtk_modules}
  INSTALL_HEADERS   OFF
  INSTALL_EXPORT    AFAMVTK
  CMAKE_DESTINATION "${CMAKE_INSTALL_LIBDIR}/cmake/adaptive-fam")
