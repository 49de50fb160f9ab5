# The package_consumer test (cmake/hf_package.cmake): installs BUILD_DIR into WORK_DIR/prefix, configures and
# builds the project in SOURCE_DIR (tests/package) against it with compiler CXX (and LAUNCHER, e.g. ccache), and
# runs its executable; then the same for SOURCE_DIR/components, the consumer of COMPONENTS core io, whose link must
# hold none of GDAL, Ceres, OpenCL and PCL (ldd), and which must fail to configure with an unknown component, naming
# it. The installed headers must include each other as <hashfusion/...> (no quoted project include left). With
# PYTHON and PYTHON_DIR (the module's install folder, relative to the prefix), imports the installed Python module
# from there. Fails on the first step that fails.
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
file(GLOB_RECURSE installed_headers ${prefix}/include/hashfusion/*.h)
foreach(header IN LISTS installed_headers)
  file(STRINGS ${header} quoted REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  if(quoted)
    message(FATAL_ERROR "package test: ${header} still includes by a quoted path: ${quoted}")
  endif()
endforeach()
list(LENGTH installed_headers n_headers)
message(STATUS "package test: ${n_headers} installed headers include each other as <hashfusion/...>: ok")

set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
set(configure_args -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX} ${launcher}
                   -DCMAKE_PREFIX_PATH=${prefix})
step("configure" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${build} ${configure_args})
step("build" ${CMAKE_COMMAND} --build ${build})
step("run" ${build}/consumer)
message(STATUS "${step_output}")

# COMPONENTS core io: only their packages, nothing of lidar / slam / OpenCL in the link.
set(components_build ${WORK_DIR}/build_components)
file(REMOVE_RECURSE ${components_build} ${components_build}_unknown)
step("configure (COMPONENTS core io)" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/components -B ${components_build}
     ${configure_args})
step("build (COMPONENTS core io)" ${CMAKE_COMMAND} --build ${components_build})
step("run (COMPONENTS core io)" ${components_build}/components_consumer)
message(STATUS "${step_output}")
# The executable's own NEEDED entries (what its link line gave it), not ldd's transitive closure: Debian's
# OpenCV imgcodecs itself loads GDAL, whoever links it.
find_program(READELF readelf)
if(READELF)
  step("readelf (COMPONENTS core io)" ${READELF} -d ${components_build}/components_consumer)
  string(REGEX MATCHALL "Shared library: \\[[^]]+\\]" needed "${step_output}")
  list(TRANSFORM needed REPLACE "Shared library: \\[([^]]+)\\]" "\\1")
  string(REGEX MATCHALL "lib(gdal|ceres|OpenCL|pcl_)[^;]*" unwanted "${needed}")
  if(unwanted)
    message(FATAL_ERROR "package test: the COMPONENTS core io consumer links ${unwanted}")
  endif()
  list(JOIN needed " " needed)
  message(STATUS "package test: the COMPONENTS core io consumer links ${needed}: none of GDAL, Ceres, OpenCL, PCL: ok")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/components -B ${components_build}_unknown
                        ${configure_args} "-DHF_COMPONENTS=core;no_such_part"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(rc EQUAL 0 OR NOT out MATCHES "hashfusion has no component \"no_such_part\"")
  message(FATAL_ERROR "package test: COMPONENTS core no_such_part did not fail naming it (${rc}):\n${out}")
endif()
message(STATUS "package test: an unknown component fails find_package, named: ok")
if(PYTHON AND PYTHON_DIR)
  step("python import" ${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/${PYTHON_DIR} ${PYTHON} -c
       "import hashfusion as hf; assert hf.__file__.startswith('${prefix}'), hf.__file__; hf.to_open3d, hf.PointCloud; print(hf.__file__)")
  message(STATUS "${step_output}")
endif()
