# The package_consumer test (cmake/hf_package.cmake): installs BUILD_DIR into WORK_DIR/prefix, configures and
# builds the project in SOURCE_DIR (tests/package) against it with compiler CXX (and LAUNCHER, e.g. ccache), and
# runs its executable; with PYTHON and PYTHON_DIR (the module's install folder, relative to the prefix), imports the
# installed Python module from there. Fails on the first step that fails.
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR CXX)
  if(NOT ${var})
    message(FATAL_ERROR "run_package_test.cmake: -D${var}= is required")
  endif()
endforeach()
set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${prefix} ${build})

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "package test: ${what} failed (${rc}):\n${out}")
  endif()
  message(STATUS "package test: ${what}: ok")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

step("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
step("configure" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${build} -G Ninja -DCMAKE_BUILD_TYPE=Release
     -DCMAKE_CXX_COMPILER=${CXX} ${launcher} -DCMAKE_PREFIX_PATH=${prefix})
step("build" ${CMAKE_COMMAND} --build ${build})
step("run" ${build}/consumer)
message(STATUS "${step_output}")
if(PYTHON AND PYTHON_DIR)
  step("python import" ${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/${PYTHON_DIR} ${PYTHON} -c
       "import hashfusion as hf; assert hf.__file__.startswith('${prefix}'), hf.__file__; print(hf.__file__)")
  message(STATUS "${step_output}")
endif()
