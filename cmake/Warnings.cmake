# Warnings on and clean for our own targets: call tomograin_warnings(target).
function(tomograin_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
endfunction()

# A module library: tomograin_module(NAME [UNITY] SOURCES... DEPS ...)
# UNITY compiles the module's sources as one translation unit per 8 files
# (CMake's unity build): for modules whose files each instantiate the same
# heavy header code (nlohmann::json, CLI11, Eigen, OpenCV), that code is
# parsed and generated once per batch instead of once per file. Names in a
# file's anonymous namespace must then be unique within the module.
function(tomograin_module name)
  cmake_parse_arguments(M "UNITY" "" "SOURCES;DEPS" ${ARGN})
  add_library(tg_${name} STATIC ${M_SOURCES})
  add_library(tomograin::${name} ALIAS tg_${name})
  target_include_directories(tg_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(tg_${name} PUBLIC ${M_DEPS})
  tomograin_warnings(tg_${name})
  if(M_UNITY)
    set_target_properties(tg_${name} PROPERTIES UNITY_BUILD ON)
  endif()
endfunction()

# Code that only wires the libraries together (the command line, the test
# suites): in the sanitizer build it is compiled at -O0, because the tests'
# time is spent in the libraries (still -O1) while these files' generated
# code (GoogleTest, CLI11, json) is what made the sanitizer build the longest
# stage of `make test`.
function(tomograin_glue target)
  if(TOMOGRAIN_SANITIZE)
    target_compile_options(${target} PRIVATE -O0)
  endif()
endfunction()

# A GoogleTest suite: tomograin_test(NAME SOURCES... DEPS ... [SLOW filter] [HOT files...]),
# registered with ctest, one ctest test per TEST. SLOW is a GoogleTest filter
# (patterns joined by ':', e.g. "SynthAccuracy.*:Pluviation.Press*") of the
# tests that take over ~10 s in Release (minutes under the sanitizers): they
# get the label `slow` instead of `unit`, and the sanitizer stage of
# `make test` leaves them out (-LE slow); the Release stage runs them.
function(tomograin_test name)
  cmake_parse_arguments(T "" "SLOW" "SOURCES;DEPS;LABELS;HOT" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_DEPS} GTest::gtest GTest::gtest_main)
  tomograin_warnings(${name})
  tomograin_glue(${name})
  # HOT: test files that instantiate library templates (volumes, partial
  # volume, CGAL) and run them on sizeable data: -O1 like the libraries under
  # the sanitizers (at -O0 OrientedBox.SeedMakesItReproducible took 26 s, not 1.6).
  if(TOMOGRAIN_SANITIZE AND T_HOT)
    set_source_files_properties(${T_HOT} PROPERTIES COMPILE_OPTIONS -O1)
  endif()
  # The suite's other files compile in unity batches, as the modules do:
  # GoogleTest's and the libraries' header code is generated once per batch
  # (the suites were ~30 % of each build). HOT files stay out in every build,
  # so that the batches, and the names they must keep unique, are the same
  # with and without the sanitizers.
  set_target_properties(${name} PROPERTIES UNITY_BUILD ON)
  if(T_HOT)
    set_source_files_properties(${T_HOT} PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  endif()
  include(GoogleTest)
  set(env "TOMOGRAIN_SOURCE_DIR=${PROJECT_SOURCE_DIR}")
  if(T_SLOW)
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 TEST_FILTER "-${T_SLOW}"
      PROPERTIES LABELS "unit;${T_LABELS}" ENVIRONMENT "${env}")
    # One label only: GoogleTestAddTests.cmake (CMake 3.25) flattens a list
    # value into separate arguments ("LABELS unit slow" sets no label slow).
    # COST: ctest -j starts the costliest tests first, so that a long test
    # declared last does not run alone at the end of the stage.
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 TEST_FILTER "${T_SLOW}"
      PROPERTIES LABELS "slow" COST 20 ENVIRONMENT "${env}")
  else()
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
      PROPERTIES LABELS "unit;${T_LABELS}" ENVIRONMENT "${env}")
  endif()
endfunction()
