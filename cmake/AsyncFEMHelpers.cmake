# SPDX-License-Identifier: BSD-3-Clause
# One way to create every library, utility and test of AsyncFEM.

include_guard(GLOBAL)
include(GNUInstallDirs)

set(ASYNCFEM_WARNING_FLAGS -Wall -Wextra -Wpedantic)

# asyncfem_add_library(NAME SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...] [HEADER_ONLY])
# Creates target asyncfem_<NAME> with alias asyncfem::<NAME>, public headers in
# libraries/<NAME>/include, install and export rules.
function(asyncfem_add_library name)
  cmake_parse_arguments(ARG "HEADER_ONLY" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  set(target asyncfem_${name})
  if(ARG_HEADER_ONLY)
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE
      $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_link_libraries(${target} INTERFACE ${ARG_PUBLIC_DEPS})
    target_compile_features(${target} INTERFACE cxx_std_20)
  else()
    add_library(${target} ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC
      $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
      PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
    target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
    target_compile_features(${target} PUBLIC cxx_std_20)
    target_compile_options(${target} PRIVATE ${ASYNCFEM_WARNING_FLAGS})
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON UNITY_BUILD ${ASYNCFEM_UNITY_BUILD})
    if(ASYNCFEM_SANITIZE)
      # Sanitized static libraries need the sanitizer runtimes wherever they are linked,
      # including projects that find the installed package.
      target_link_options(${target} INTERFACE -fsanitize=address,undefined)
    endif()
  endif()
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  add_library(asyncfem::${name} ALIAS ${target})
  install(TARGETS ${target} EXPORT AsyncFEMTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# asyncfem_add_utility(NAME SOURCES ... DEPS ...): an executable in build/bin.
function(asyncfem_add_utility name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_compile_options(${name} PRIVATE ${ASYNCFEM_WARNING_FLAGS})
  set_target_properties(${name} PROPERTIES UNITY_BUILD ${ASYNCFEM_UNITY_BUILD})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# asyncfem_test_optimization(TARGET): a test executable compiles at ASYNCFEM_TEST_OPTIMIZATION
# in optimized builds (the last -O on the command line wins).
function(asyncfem_test_optimization target)
  if(ASYNCFEM_TEST_OPTIMIZATION)
    target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo>:${ASYNCFEM_TEST_OPTIMIZATION}>)
  endif()
endfunction()

# asyncfem_add_test(NAME SOURCES ... DEPS ...): a GoogleTest executable registered with CTest.
function(asyncfem_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_options(${name} PRIVATE ${ASYNCFEM_WARNING_FLAGS})
  asyncfem_test_optimization(${name})
  target_compile_definitions(${name} PRIVATE
    ASYNCFEM_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data"
    ASYNCFEM_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
    ASYNCFEM_BIN_DIR="${CMAKE_RUNTIME_OUTPUT_DIRECTORY}")
  # Idle OpenMP threads sleep rather than spin (see asyncfem/core/threading.hpp).
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 600 ENVIRONMENT OMP_WAIT_POLICY=passive)
endfunction()
