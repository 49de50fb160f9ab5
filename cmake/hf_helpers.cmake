# hf_library(NAME SOURCES... DEPS ...): one library target per source folder, our warnings, the repo root on the
# include path so every include reads "core/se3.h", "io/ply.h", ... Every such library is listed in the global
# property HF_LIBRARIES, from which cmake/hf_package.cmake installs and exports it (hashfusion::NAME without "hf_",
# headers under include/hashfusion, included there as <hashfusion/core/se3.h>; the installed include folder is set
# by hf_package.cmake). With HF_LIBRARIES_PIC the objects are position-independent, so the Python module (a shared
# object) can link them.
function(hf_library name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${A_SOURCES})
  target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>)
  target_link_libraries(${name} PUBLIC ${A_DEPS} PRIVATE $<BUILD_INTERFACE:hf_warnings>)
  if(HF_LIBRARIES_PIC)
    # -fPIC alone would make every function interposable (no inlining across them); nothing interposes ours.
    set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    target_compile_options(${name} PRIVATE $<$<CXX_COMPILER_ID:GNU>:-fno-semantic-interposition>)
  endif()
  set_property(GLOBAL APPEND PROPERTY HF_LIBRARIES ${name})
endfunction()

# hf_test(NAME SOURCES... DEPS ...): a GoogleTest executable registered with CTest. Tests find ../shared through
# HF_SHARED_DIR (the folder beside the repo) and skip with a message when it is absent.
#
# Build time: every test reuses one precompiled header (GoogleTest, Eigen and the standard headers the tests use)
# from the target hf_test_pch, which is compiled with the flags every test shares: our warnings, the two
# definitions below, GoogleTest and Eigen. A test may add definitions of its own (clang and gcc accept extra
# command-line macros the header does not use); it must not redefine these. HF_PCH=OFF turns this off.
# Under HF_FUZZ the tests get no libFuzzer coverage instrumentation: only the parser sources listed in
# HF_FUZZ_INSTRUMENTED (CMakeLists.txt) do.
function(hf_test_common_flags name)
  target_link_libraries(${name} PRIVATE GTest::gtest Eigen3::Eigen hf_warnings)
  target_compile_definitions(${name} PRIVATE
    HF_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared"
    HF_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endfunction()

# Test executables are shared by folder (HF_UNITY, build time: one link and, with unity batches, a few compiles
# instead of one per test file): every hf_test of a folder with the same LABELS and no ENVIRONMENT adds its sources
# and DEPS to that folder's executable (hf_tests_FOLDER[_LABELS]), and NAME becomes an ALIAS of it, so
# $<TARGET_FILE:NAME> still runs those tests (with the others of the folder: filter with --gtest_filter). CTest
# sees one test per GoogleTest suite, run in its own process (cmake/hf_gtest_suites.cmake). A test with
# ENVIRONMENT keeps its own executable. Extra link or include needs go through DEPS / SYSTEM_INCLUDES, not
# target_* calls on NAME.
function(hf_test name)
  cmake_parse_arguments(A "" "COST" "SOURCES;DEPS;LABELS;ENVIRONMENT;SYSTEM_INCLUDES" ${ARGN})
  # The sanitizer suite leaves release_only tests out (CMakePresets.json): its build does not compile them either.
  if(HF_SANITIZE AND "release_only" IN_LIST A_LABELS)
    return()
  endif()
  if(HF_UNITY AND NOT A_ENVIRONMENT)
    file(RELATIVE_PATH folder ${PROJECT_SOURCE_DIR}/tests ${CMAKE_CURRENT_SOURCE_DIR})
    string(REPLACE "/" "_" group "hf_tests_${folder}")
    if(A_LABELS AND NOT A_LABELS STREQUAL folder)
      string(REPLACE ";" "_" labels "${A_LABELS}")
      string(APPEND group "_${labels}")
    endif()
    if(A_COST)
      string(APPEND group "_cost${A_COST}")
    endif()
    if(NOT TARGET ${group})
      hf_test_executable(${group} LABELS "${A_LABELS}" COST "${A_COST}")
    endif()
    target_sources(${group} PRIVATE ${A_SOURCES})
    target_link_libraries(${group} PRIVATE ${A_DEPS})
    if(A_SYSTEM_INCLUDES)
      target_include_directories(${group} SYSTEM PRIVATE ${A_SYSTEM_INCLUDES})
    endif()
    add_executable(${name} ALIAS ${group})
    return()
  endif()
  hf_test_executable(${name} SOURCES ${A_SOURCES} LABELS "${A_LABELS}" ENVIRONMENT "${A_ENVIRONMENT}"
                     COST "${A_COST}")
  target_link_libraries(${name} PRIVATE ${A_DEPS})
  if(A_SYSTEM_INCLUDES)
    target_include_directories(${name} SYSTEM PRIVATE ${A_SYSTEM_INCLUDES})
  endif()
endfunction()

function(hf_test_executable name)
  cmake_parse_arguments(A "" "COST" "SOURCES;LABELS;ENVIRONMENT" ${ARGN})
  add_executable(${name} ${A_SOURCES})
  if(NOT TARGET hf_gtest_suite_main)
    add_library(hf_gtest_suite_main OBJECT ${PROJECT_SOURCE_DIR}/tests/common/gtest_suite_main.cpp)
    target_link_libraries(hf_gtest_suite_main PUBLIC GTest::gtest PRIVATE hf_warnings)
  endif()
  target_link_libraries(${name} PRIVATE hf_gtest_suite_main)
  hf_test_common_flags(${name})
  if(HF_PCH)
    if(NOT TARGET hf_test_pch)
      file(CONFIGURE OUTPUT ${PROJECT_BINARY_DIR}/hf_test_pch.cpp
           CONTENT "// Carrier of the tests' precompiled header (cmake/hf_helpers.cmake).\n")
      add_library(hf_test_pch OBJECT ${PROJECT_BINARY_DIR}/hf_test_pch.cpp)
      hf_test_common_flags(hf_test_pch)
      target_precompile_headers(hf_test_pch PRIVATE
        <gtest/gtest.h> <Eigen/Core> <Eigen/Geometry>
        <algorithm> <cmath> <cstdint> <filesystem> <fstream> <functional> <random> <sstream> <string> <vector>)
    endif()
    target_precompile_headers(${name} REUSE_FROM hf_test_pch)
  endif()
  # One CTest test per GoogleTest suite (cmake/hf_gtest_suites.cmake says why), discovered after each link like
  # gtest_discover_tests does. The main() (tests/common/gtest_suite_main.cpp) exits 77 when a suite only skipped.
  # ENVIRONMENT: VAR=value entries for the tests' processes (over the test preset's environment).
  # COST: CTest starts tests in descending cost; on a fresh clone it has no timings of its own yet, so the few
  # tests of a minute or more say so and start first instead of ending the suite alone on one core.
  set(properties "")
  if(A_LABELS)
    string(APPEND properties " LABELS [==[${A_LABELS}]==]")
  endif()
  if(A_ENVIRONMENT)
    string(APPEND properties " ENVIRONMENT [==[${A_ENVIRONMENT}]==]")
  endif()
  if(A_COST)
    string(APPEND properties " COST ${A_COST}")
  endif()
  set(props_file ${CMAKE_CURRENT_BINARY_DIR}/${name}_suite_properties.cmake)
  file(CONFIGURE OUTPUT ${props_file} CONTENT "set(HF_TEST_PROPERTIES_TEXT [===[@properties@]===])\n" @ONLY)
  set(ctest_file ${CMAKE_CURRENT_BINARY_DIR}/${name}_suites.cmake)
  add_custom_command(TARGET ${name} POST_BUILD
    COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:${name}> -DOUT=${ctest_file} -DWORKDIR=${CMAKE_CURRENT_BINARY_DIR}
            -DPROPS=${props_file} -P ${PROJECT_SOURCE_DIR}/cmake/hf_gtest_suites.cmake
    VERBATIM)
  set(include_file ${CMAKE_CURRENT_BINARY_DIR}/${name}_suites_include.cmake)
  file(CONFIGURE OUTPUT ${include_file} CONTENT
"if(EXISTS [==[@ctest_file@]==])
  include([==[@ctest_file@]==])
else()
  add_test(@name@_NOT_BUILT @name@_NOT_BUILT)
endif()
" @ONLY)
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${include_file})
endfunction()

# hf_fuzzer(NAME SOURCES... DEPS ... [SECONDS n, default HF_FUZZ_SECONDS]): a libFuzzer target (clang, HF_FUZZ=ON) plus a CTest test that
# runs it for a short bounded time on an empty corpus seeded from tests/fuzz/corpus/NAME when that folder exists.
# Without HF_FUZZ the same source is built into a plain driver that replays the seed corpus, so every build at
# least exercises the seeds through the parser.
function(hf_fuzzer name)
  cmake_parse_arguments(A "" "SECONDS" "SOURCES;DEPS" ${ARGN})
  if(NOT A_SECONDS)
    set(A_SECONDS ${HF_FUZZ_SECONDS})
  endif()
  set(corpus_src ${PROJECT_SOURCE_DIR}/tests/fuzz/corpus/${name})
  if(HF_FUZZ)
    add_executable(${name} ${A_SOURCES})
    target_compile_options(${name} PRIVATE -fsanitize=fuzzer)
    target_link_options(${name} PRIVATE -fsanitize=fuzzer)
    target_link_libraries(${name} PRIVATE ${A_DEPS} hf_warnings)
    set(work ${CMAKE_CURRENT_BINARY_DIR}/${name}_corpus)
    add_test(NAME ${name}
      COMMAND ${CMAKE_COMMAND} -E env ${CMAKE_COMMAND} -DFUZZER=$<TARGET_FILE:${name}> -DWORK=${work}
              -DSEEDS=${corpus_src} -DSECONDS=${A_SECONDS} -P ${PROJECT_SOURCE_DIR}/cmake/run_fuzzer.cmake)
    set_tests_properties(${name} PROPERTIES LABELS fuzz TIMEOUT 300)
  else()
    add_executable(${name} ${A_SOURCES} ${PROJECT_SOURCE_DIR}/tests/fuzz/replay_main.cpp)
    target_link_libraries(${name} PRIVATE ${A_DEPS} hf_warnings)
    add_test(NAME ${name} COMMAND ${name} ${corpus_src})
    set_tests_properties(${name} PROPERTIES LABELS fuzz)
  endif()
endfunction()

# hf_fuzz_instrument_sources(TARGET SOURCE [TARGET SOURCE ...]): gives each SOURCE (relative to the repo root) of
# library TARGET libFuzzer's coverage instrumentation (-fsanitize=fuzzer-no-link), so the fuzzers are guided
# through the parsers without slowing the rest of the code. Called deferred from CMakeLists.txt under HF_FUZZ, once
# every target exists; a pair whose target or file is absent (a folder not built yet) is skipped.
function(hf_fuzz_instrument_sources)
  set(args ${ARGN})
  list(LENGTH args n)
  math(EXPR last "${n} - 1")
  foreach(i RANGE 0 ${last} 2)
    math(EXPR j "${i} + 1")
    list(GET args ${i} target)
    list(GET args ${j} source)
    set(file ${PROJECT_SOURCE_DIR}/${source})
    if(TARGET ${target} AND EXISTS ${file})
      get_target_property(sources ${target} SOURCES)
      get_target_property(dir ${target} SOURCE_DIR)
      cmake_path(RELATIVE_PATH file BASE_DIRECTORY ${dir} OUTPUT_VARIABLE relative)
      if(NOT relative IN_LIST sources AND NOT file IN_LIST sources)
        message(WARNING "HF_FUZZ_INSTRUMENTED: ${source} is not a source of ${target}; not instrumented")
        continue()
      endif()
      set_property(SOURCE ${file} TARGET_DIRECTORY ${target} APPEND PROPERTY COMPILE_OPTIONS
                   -fsanitize=fuzzer-no-link)
    endif()
  endforeach()
endfunction()
