# SPDX-License-Identifier: BSD-3-Clause
# cmake -DAFAM_BINARIES=<exe;exe;...> -P AFAMCheckNoParaViewLinked.cmake
# The plain-VTK build's promise, checked on what the loader really resolves: every binary links
# VTK's libraries (at least vtkCommonCore) and none of ParaView's own (its server manager, views,
# Qt components, IceT, Catalyst), which share the -pv5.11 suffix on Debian.
if (NOT AFAM_BINARIES)
  message(FATAL_ERROR "pass -DAFAM_BINARIES=<executables>")
endif ()
find_program(_ldd ldd REQUIRED)
set(_paraview "lib(pq[A-Z][A-Za-z]*|vtkPV[A-Za-z0-9]*|vtkRemoting[A-Za-z]*|vtkIceT[A-Za-z]*|vtkParaView[A-Za-z]*|vtkqttesting|vtkUtilitiesPythonInitializer)[-.]")
# The pattern must catch a ParaView library name, or the check could pass by matching nothing.
if (NOT "libvtkRemotingViews-pv5.11.so.1" MATCHES "${_paraview}" OR
    NOT "libpqCore-pv5.11.so.1" MATCHES "${_paraview}" OR
    "libvtkRenderingOpenGL2-pv5.11.so.1" MATCHES "${_paraview}")
  message(FATAL_ERROR "the ParaView library pattern is broken")
endif ()
foreach (_binary IN LISTS AFAM_BINARIES)
  execute_process(COMMAND "${_ldd}" "${_binary}" OUTPUT_VARIABLE _out RESULT_VARIABLE _rc)
  if (NOT _rc EQUAL 0)
    message(FATAL_ERROR "ldd ${_binary} failed (${_rc})")
  endif ()
  string(REGEX MATCHALL "[^ \t\n]+\\.so[^ \t\n]*" _libs "${_out}")
  set(_vtk 0)
  set(_bad "")
  foreach (_lib IN LISTS _libs)
    get_filename_component(_name "${_lib}" NAME)
    if (_name MATCHES "${_paraview}")
      list(APPEND _bad "${_name}")
    elseif (_name MATCHES "^libvtkCommonCore")
      set(_vtk 1)
    endif ()
  endforeach ()
  if (_bad)
    list(REMOVE_DUPLICATES _bad)
    message(FATAL_ERROR "${_binary} links ParaView libraries: ${_bad}")
  endif ()
  if (NOT _vtk)
    message(FATAL_ERROR "${_binary} does not link vtkCommonCore: not a VTK binary, nothing checked")
  endif ()
  message(STATUS "${_binary}: VTK only")
endforeach ()
