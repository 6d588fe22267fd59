# viosfm_add_library(NAME SRCS ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates the target viosfm_<NAME> (alias viosfm::<NAME>) for one layer folder.
function(viosfm_add_library NAME)
  cmake_parse_arguments(ARG "" "" "SRCS;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  set(target viosfm_${NAME})
  add_library(${target} ${ARG_SRCS})
  add_library(viosfm::${NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_compile_features(${target} PUBLIC cxx_std_20)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
endfunction()

# viosfm_add_test(MODULE NAME [DEPS ...])
# Builds NAME.cc of the current folder into a GoogleTest binary registered
# with ctest as MODULE/NAME. A binary whose every test calls GTEST_SKIP (e.g.
# its dataset is absent) is reported as skipped (exit code 77, see
# util/testing_main.cc); a binary with some skipped tests passes, and fails
# if any test fails.
function(viosfm_add_test MODULE NAME)
  if(NOT VIOSFM_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  set(target test_${MODULE}_${NAME})
  add_executable(${target} ${NAME}.cc)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  target_compile_definitions(${target} PRIVATE
    VIOSFM_DATA_DIR="${VIOSFM_DATA_DIR}"
    VIOSFM_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  target_link_libraries(${target} PRIVATE viosfm_${MODULE} viosfm_testing ${ARG_DEPS})
  add_test(NAME ${MODULE}/${NAME} COMMAND ${target})
  set_tests_properties(${MODULE}/${NAME} PROPERTIES
    SKIP_RETURN_CODE 77
    WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
endfunction()

# viosfm_add_layer(NAME [PUBLIC_DEPS ...] [PRIVATE_DEPS ...] [TEST_DEPS ...])
# One library per layer folder: every *.cc of the folder except *_test.cc and
# *_benchmark.cc goes into viosfm_<NAME>; every *_test.cc becomes the ctest
# test <NAME>/<file>.
function(viosfm_add_layer NAME)
  cmake_parse_arguments(ARG "" "" "PUBLIC_DEPS;PRIVATE_DEPS;TEST_DEPS" ${ARGN})
  # Links only downward (cmake/ViosfmLayers.cmake); tests may link the simulator.
  list(FIND VIOSFM_LAYERS ${NAME} own)
  foreach(dep ${ARG_PUBLIC_DEPS} ${ARG_PRIVATE_DEPS})
    if(dep MATCHES "^viosfm_(.+)$")
      list(FIND VIOSFM_LAYERS ${CMAKE_MATCH_1} index)
      if(own EQUAL -1 OR index EQUAL -1 OR NOT index LESS own)
        message(FATAL_ERROR "layer ${NAME} links ${dep}, not a lower layer "
                            "(cmake/ViosfmLayers.cmake: ${VIOSFM_LAYERS})")
      endif()
    endif()
  endforeach()
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cc)
  list(FILTER sources EXCLUDE REGEX "_(test|benchmark)\\.cc$")
  if(sources)
    viosfm_add_library(${NAME} SRCS ${sources}
      PUBLIC_DEPS ${ARG_PUBLIC_DEPS} PRIVATE_DEPS ${ARG_PRIVATE_DEPS})
  else()
    # A header-only layer.
    add_library(viosfm_${NAME} INTERFACE)
    add_library(viosfm::${NAME} ALIAS viosfm_${NAME})
    target_include_directories(viosfm_${NAME} INTERFACE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(viosfm_${NAME} INTERFACE ${ARG_PUBLIC_DEPS})
  endif()
  file(GLOB tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*_test.cc)
  foreach(test ${tests})
    get_filename_component(test_name ${test} NAME_WE)
    viosfm_add_test(${NAME} ${test_name} DEPS ${ARG_TEST_DEPS})
  endforeach()
  file(GLOB benchmarks CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*_benchmark.cc)
  foreach(bench ${benchmarks})
    get_filename_component(bench_name ${bench} NAME_WE)
    viosfm_add_benchmark(${NAME} ${bench_name} DEPS ${ARG_TEST_DEPS})
  endforeach()
endfunction()

# viosfm_add_benchmark(MODULE NAME [DEPS ...])
# Builds NAME.cc (Google Benchmark) into bench_MODULE_NAME, collected by the
# `viosfm_benchmarks` target; benchmarks are not ctest tests (timings are
# measured, never asserted).
function(viosfm_add_benchmark MODULE NAME)
  if(NOT VIOSFM_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  set(target bench_${MODULE}_${NAME})
  add_executable(${target} EXCLUDE_FROM_ALL ${NAME}.cc)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  target_compile_definitions(${target} PRIVATE
    VIOSFM_DATA_DIR="${VIOSFM_DATA_DIR}" VIOSFM_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  target_link_libraries(${target} PRIVATE viosfm_${MODULE} ${ARG_DEPS} benchmark::benchmark_main)
  add_dependencies(viosfm_benchmarks ${target})
endfunction()
