# Warnings on and clean for our own targets: call tomograin_warnings(target).
function(tomograin_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
endfunction()

# A module library: tomograin_module(NAME SOURCES... DEPS ...)
function(tomograin_module name)
  cmake_parse_arguments(M "" "" "SOURCES;DEPS" ${ARGN})
  add_library(tg_${name} STATIC ${M_SOURCES})
  add_library(tomograin::${name} ALIAS tg_${name})
  target_include_directories(tg_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(tg_${name} PUBLIC ${M_DEPS})
  tomograin_warnings(tg_${name})
endfunction()

# A GoogleTest suite: tomograin_test(NAME SOURCES... DEPS ...), registered with ctest.
function(tomograin_test name)
  cmake_parse_arguments(T "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_DEPS} GTest::gtest GTest::gtest_main)
  tomograin_warnings(${name})
  include(GoogleTest)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "unit;${T_LABELS}" ENVIRONMENT "TOMOGRAIN_SOURCE_DIR=${PROJECT_SOURCE_DIR}")
endfunction()
