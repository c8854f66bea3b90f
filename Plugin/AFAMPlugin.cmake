# SPDX-License-Identifier: BSD-3-Clause
# The plugin itself (declared by the root paraview.plugin). Included from the staged plugin folder
# (see Plugin/CMakeLists.txt), so every path here is absolute.
paraview_add_plugin(AdaptiveFAM
  VERSION            "${PROJECT_VERSION}"
  MODULES            AFAM::vtkAFAM AFAM::vtkAFAMParaView
  MODULE_FILES       "${AFAM_STAGED_MODULE_FILE}" "${CMAKE_CURRENT_LIST_DIR}/Representation/vtk.module"
  SERVER_MANAGER_XML "${CMAKE_CURRENT_LIST_DIR}/AdaptiveFAM.xml"
  XML_DOCUMENTATION  OFF)
