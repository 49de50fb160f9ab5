# hf_library(NAME SOURCES... DEPS ...): one library target per source folder, our warnings, the repo root on the
# include path so every include reads "core/se3.h", "io/ply.h", ...
function(hf_library name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${A_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${A_DEPS} PRIVATE hf_warnings)
endfunction()

# hf_test(NAME SOURCES... DEPS ...): a GoogleTest executable registered with CTest. Tests find ../shared through
# HF_SHARED_DIR (the folder beside the repo) and skip with a message when it is absent.
function(hf_test name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_DEPS} GTest::gtest GTest::gtest_main hf_warnings)
  target_compile_definitions(${name} PRIVATE
    HF_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared"
    HF_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  include(GoogleTest)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${A_LABELS}")
endfunction()

# hf_fuzzer(NAME SOURCES... DEPS ... [SECONDS n]): a libFuzzer target (clang, HF_FUZZ=ON) plus a CTest test that
# runs it for a short bounded time on an empty corpus seeded from tests/fuzz/corpus/NAME when that folder exists.
# Without HF_FUZZ the same source is built into a plain driver that replays the seed corpus, so every build at
# least exercises the seeds through the parser.
function(hf_fuzzer name)
  cmake_parse_arguments(A "" "SECONDS" "SOURCES;DEPS" ${ARGN})
  if(NOT A_SECONDS)
    set(A_SECONDS 10)
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
