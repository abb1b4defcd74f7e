# SPDX-License-Identifier: BSD-3-Clause
# Finds off-screen Mesa (Debian's libosmesa6-dev). Creates OSMesa::OSMesa.
include(FindPackageHandleStandardArgs)
find_path(OSMesa_INCLUDE_DIR GL/osmesa.h)
find_library(OSMesa_LIBRARY OSMesa)
mark_as_advanced(OSMesa_INCLUDE_DIR OSMesa_LIBRARY)
find_package_handle_standard_args(OSMesa REQUIRED_VARS OSMesa_LIBRARY OSMesa_INCLUDE_DIR)
if(OSMesa_FOUND AND NOT TARGET OSMesa::OSMesa)
  add_library(OSMesa::OSMesa UNKNOWN IMPORTED)
  set_target_properties(OSMesa::OSMesa PROPERTIES
    IMPORTED_LOCATION "${OSMesa_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OSMesa_INCLUDE_DIR}")
endif()
