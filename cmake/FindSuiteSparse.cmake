# SPDX-License-Identifier: BSD-3-Clause
# Finds the SuiteSparse components AsyncFEM uses (Debian's libsuitesparse-dev).
# Components: CHOLMOD UMFPACK (default: both). Creates SuiteSparse::<component>
# plus SuiteSparse::config; sets SuiteSparse_FOUND.

include(FindPackageHandleStandardArgs)

if(NOT SuiteSparse_FIND_COMPONENTS)
  set(SuiteSparse_FIND_COMPONENTS CHOLMOD UMFPACK)
endif()

find_path(SuiteSparse_INCLUDE_DIR SuiteSparse_config.h PATH_SUFFIXES suitesparse)
find_library(SuiteSparse_config_LIBRARY suitesparseconfig)
mark_as_advanced(SuiteSparse_INCLUDE_DIR SuiteSparse_config_LIBRARY)

if(SuiteSparse_INCLUDE_DIR AND SuiteSparse_config_LIBRARY AND NOT TARGET SuiteSparse::config)
  add_library(SuiteSparse::config UNKNOWN IMPORTED)
  set_target_properties(SuiteSparse::config PROPERTIES
    IMPORTED_LOCATION "${SuiteSparse_config_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${SuiteSparse_INCLUDE_DIR}")
endif()

set(_ss_required SuiteSparse_INCLUDE_DIR SuiteSparse_config_LIBRARY)
foreach(comp IN LISTS SuiteSparse_FIND_COMPONENTS)
  string(TOLOWER ${comp} lib)
  find_path(SuiteSparse_${comp}_INCLUDE_DIR ${lib}.h PATH_SUFFIXES suitesparse)
  find_library(SuiteSparse_${comp}_LIBRARY ${lib})
  mark_as_advanced(SuiteSparse_${comp}_INCLUDE_DIR SuiteSparse_${comp}_LIBRARY)
  if(SuiteSparse_${comp}_INCLUDE_DIR AND SuiteSparse_${comp}_LIBRARY)
    set(SuiteSparse_${comp}_FOUND TRUE)
    if(NOT TARGET SuiteSparse::${comp})
      add_library(SuiteSparse::${comp} UNKNOWN IMPORTED)
      set_target_properties(SuiteSparse::${comp} PROPERTIES
        IMPORTED_LOCATION "${SuiteSparse_${comp}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${SuiteSparse_${comp}_INCLUDE_DIR}"
        INTERFACE_LINK_LIBRARIES SuiteSparse::config)
    endif()
  else()
    set(SuiteSparse_${comp}_FOUND FALSE)
  endif()
endforeach()

find_package_handle_standard_args(SuiteSparse
  REQUIRED_VARS ${_ss_required}
  HANDLE_COMPONENTS)
