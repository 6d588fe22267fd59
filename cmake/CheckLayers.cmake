# Checks that no file of src/viosfm/ includes a header of a higher layer
# (cmake/ViosfmLayers.cmake). Tests, benchmarks and test fixtures
# (*_test.cc, *_benchmark.cc, *_test_fixture.h) may also include the
# simulator (sim/). Fails naming every offending include.
# Usage: cmake -DSOURCE_DIR=<repository> -P cmake/CheckLayers.cmake
include(${CMAKE_CURRENT_LIST_DIR}/ViosfmLayers.cmake)
if(NOT SOURCE_DIR)
  message(FATAL_ERROR "CheckLayers.cmake: pass -DSOURCE_DIR=<repository>")
endif()
file(GLOB_RECURSE files RELATIVE ${SOURCE_DIR}/src/viosfm
     ${SOURCE_DIR}/src/viosfm/*.h ${SOURCE_DIR}/src/viosfm/*.cc)
set(violations "")
set(num_files 0)
set(num_includes 0)
foreach(file ${files})
  string(REGEX MATCH "^[^/]+" layer "${file}")
  list(FIND VIOSFM_LAYERS "${layer}" own)
  if(own EQUAL -1)
    continue()  # a file outside the layer folders
  endif()
  math(EXPR num_files "${num_files} + 1")
  set(is_test FALSE)
  if(file MATCHES "_(test|benchmark)\\.cc$" OR file MATCHES "_test_fixture\\.h$")
    set(is_test TRUE)
  endif()
  file(STRINGS ${SOURCE_DIR}/src/viosfm/${file} lines REGEX "^#include \"viosfm/")
  foreach(line ${lines})
    string(REGEX MATCH "viosfm/([^/]+)/" unused "${line}")
    set(target "${CMAKE_MATCH_1}")
    list(FIND VIOSFM_LAYERS "${target}" index)
    math(EXPR num_includes "${num_includes} + 1")
    if(index EQUAL -1)
      list(APPEND violations "${file}: ${line} (no such layer)")
    elseif(index GREATER own AND NOT (is_test AND target STREQUAL "sim"))
      list(APPEND violations "${file}: ${line} (${layer} is below ${target})")
    endif()
  endforeach()
endforeach()
if(violations)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "includes of a higher layer (order: ${VIOSFM_LAYERS}):\n  ${text}")
endif()
message(STATUS "layers: ${num_files} files, ${num_includes} includes of viosfm headers, "
               "every one of its own or a lower layer")
