# SPDX-License-Identifier: BSD-3-Clause
# Helpers shared by every module, test and benchmark target.
#
# Headers live beside their sources in lib/<module>/ and are included as
# "nurbsfront/<module>/<file>.h": the build tree gets a link include/nurbsfront -> lib/.

set(NURBSFRONT_INCLUDE_ROOT "${PROJECT_BINARY_DIR}/include")
file(MAKE_DIRECTORY "${NURBSFRONT_INCLUDE_ROOT}")
if(NOT EXISTS "${NURBSFRONT_INCLUDE_ROOT}/nurbsfront")
  file(CREATE_LINK "${PROJECT_SOURCE_DIR}/lib" "${NURBSFRONT_INCLUDE_ROOT}/nurbsfront" SYMBOLIC)
endif()

# Warnings and sanitizers, applied per target (never globally).
function(nurbsfront_target_defaults target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local)
  if(NURBSFRONT_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(NURBSFRONT_SANITIZE)
    target_compile_options(${target} PUBLIC -fsanitize=${NURBSFRONT_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
    target_link_options(${target} PUBLIC -fsanitize=${NURBSFRONT_SANITIZE})
  endif()
endfunction()

# nurbsfront_add_module(<name> SOURCES <files...> DEPS <targets...>)
# creates nurbsfront_<name> with alias nurbsfront::<name>.
function(nurbsfront_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target nurbsfront_${name})
  add_library(${target} STATIC ${ARG_SOURCES})
  add_library(nurbsfront::${name} ALIAS ${target})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${NURBSFRONT_INCLUDE_ROOT}>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON EXPORT_NAME ${name})
  nurbsfront_target_defaults(${target})
  set_property(GLOBAL APPEND PROPERTY NURBSFRONT_MODULES ${target})
endfunction()

# nurbsfront_add_test(<name> SOURCES <files...> DEPS <targets...>)
# One GoogleTest runner. Test suites whose name contains "Slow" get the ctest label
# "slow", all others "fast": `ctest -L fast` is the quick suite.
function(nurbsfront_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target test_${name})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} nurbsfront_test_support GTest::gtest GTest::gtest_main)
  nurbsfront_target_defaults(${target})
  gtest_discover_tests(${target}
    TEST_PREFIX "${name}."
    TEST_FILTER "-*Slow*.*"
    PROPERTIES LABELS "fast"
    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}"
    DISCOVERY_TIMEOUT 60)
  gtest_discover_tests(${target}
    TEST_PREFIX "${name}."
    TEST_FILTER "*Slow*.*"
    PROPERTIES LABELS "slow"
    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}"
    DISCOVERY_TIMEOUT 60)
endfunction()

# nurbsfront_add_bench(<name> SOURCES <files...> DEPS <targets...>)
function(nurbsfront_add_bench name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target bench_${name})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} benchmark::benchmark)
  nurbsfront_target_defaults(${target})
endfunction()
