# Install rules and the CMake package (issue 24), included by CMakeLists.txt once every library folder is added.
#
#   cmake --install build/release --prefix /opt/hashfusion
#   find_package(hashfusion REQUIRED)   # in another project, with CMAKE_PREFIX_PATH=/opt/hashfusion
#   target_link_libraries(app PRIVATE hashfusion::slam)
#
# Every hf_library (global property HF_LIBRARIES) outside bench/ and tests/ is installed and exported as
# hashfusion::NAME (NAME without "hf_": core, io, fusion, registration, slam, ...), with its folder's headers under
# include/hashfusion (so includes read "core/se3.h" as in the tree). hashfusionConfig.cmake finds the packages the
# exported targets link (find_dependency), derived from their link interfaces through HF_PACKAGE_OF below; a
# library linking anything else (a target of another package, a plain library path) stays out of the package,
# with a configure message naming it (add its package there to install it).
# Left out on purpose: HF_PACKAGE_EXCLUDE (hf_io_pcl: PCL's package drags in VTK and MPI, shared/setup/NOTES.md).
#
# The public-header check: the object library hf_header_check compiles each installed header alone in its own
# one-line translation unit (release builds; part of `all`, so a header that misses an include fails the build).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(HF_PACKAGE_EXCLUDE hf_io_pcl)
# Imported-target prefix -> the find_dependency() arguments of its package.
set(HF_PACKAGE_OF_Eigen3 "Eigen3 NO_MODULE")
set(HF_PACKAGE_OF_nlohmann_json "nlohmann_json")
set(HF_PACKAGE_OF_Threads "Threads")
set(HF_PACKAGE_OF_TBB "TBB")
set(HF_PACKAGE_OF_Ceres "Ceres")
set(HF_PACKAGE_OF_GDAL "GDAL")
set(HF_PACKAGE_OF_OpenCL "OpenCL")
set(HF_PACKAGE_OF_PNG "PNG")
set(HF_PACKAGE_OF_ZLIB "ZLIB")
set(HF_PACKAGE_OF_OpenGL "OpenGL")

# The link items of a target that are not build-tree-only, with $<LINK_ONLY:...> unwrapped.
function(hf_exported_link_items target out)
  get_target_property(items ${target} INTERFACE_LINK_LIBRARIES)
  set(result)
  foreach(item IN LISTS items)
    string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" item "${item}")
    if(item MATCHES "^\\$<BUILD_INTERFACE:" OR item STREQUAL "items-NOTFOUND")
      continue()
    endif()
    list(APPEND result "${item}")
  endforeach()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

get_property(hf_all_libraries GLOBAL PROPERTY HF_LIBRARIES)
set(hf_exported)
foreach(lib IN LISTS hf_all_libraries)
  get_target_property(dir ${lib} SOURCE_DIR)
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${dir})
  if(lib IN_LIST HF_PACKAGE_EXCLUDE OR rel MATCHES "^(bench|tests)(/|$)")
    continue()
  endif()
  list(APPEND hf_exported ${lib})
endforeach()

# The packages of the exported libraries' dependencies; a library with an unknown one is dropped (with what
# depends on it).
set(hf_dependencies)
set(hf_opencv_components)
foreach(lib IN LISTS hf_exported)
  hf_exported_link_items(${lib} items)
  set(unknown)
  set(lib_dependencies)
  set(lib_opencv)
  foreach(item IN LISTS items)
    if(item IN_LIST hf_all_libraries)
      continue()
    elseif(item MATCHES "^opencv_(.*)$")
      list(APPEND lib_opencv ${CMAKE_MATCH_1})
    endif()
    set(package)
    if(item MATCHES "^([A-Za-z0-9_]+)::")
      set(package "${HF_PACKAGE_OF_${CMAKE_MATCH_1}}")
    endif()
    if(package)
      list(APPEND lib_dependencies "${package}")
    elseif(NOT item MATCHES "^opencv_")
      list(APPEND unknown ${item})
    endif()
  endforeach()
  if(unknown)
    message(STATUS "hf_package: ${lib} is not installed: it links ${unknown}, of no package in HF_PACKAGE_OF_*")
    list(REMOVE_ITEM hf_exported ${lib})
  else()
    list(APPEND hf_dependencies ${lib_dependencies})
    list(APPEND hf_opencv_components ${lib_opencv})
  endif()
endforeach()
list(REMOVE_DUPLICATES hf_dependencies)
list(REMOVE_DUPLICATES hf_opencv_components)
set(HF_FIND_DEPENDENCIES "")
foreach(dep IN LISTS hf_dependencies)
  string(APPEND HF_FIND_DEPENDENCIES "find_dependency(${dep})\n")
endforeach()
if(hf_opencv_components)
  list(JOIN hf_opencv_components " " components)
  string(APPEND HF_FIND_DEPENDENCIES "find_dependency(OpenCV COMPONENTS ${components})\n")
endif()

# Libraries and their headers.
set(hf_public_headers)
foreach(lib IN LISTS hf_exported)
  string(REGEX REPLACE "^hf_" "" export_name ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${export_name})
  get_target_property(dir ${lib} SOURCE_DIR)
  file(GLOB_RECURSE headers CONFIGURE_DEPENDS ${dir}/*.h)
  list(APPEND hf_public_headers ${headers})
endforeach()
list(REMOVE_DUPLICATES hf_public_headers)
foreach(header IN LISTS hf_public_headers)
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${header})
  get_filename_component(rel_dir ${rel} DIRECTORY)
  install(FILES ${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hashfusion/${rel_dir})
endforeach()
install(TARGETS ${hf_exported} EXPORT hashfusionTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
# Everything `cmake --install` copies, as one target: the demo (scripts/demo.sh) builds it, so the install works
# after the README's first command as after a full build (issue 36; `cmake --install` builds nothing itself).
add_custom_target(hf_installable)
foreach(target IN LISTS hf_exported ITEMS hashfusion hf_python)
  if(TARGET ${target})
    add_dependencies(hf_installable ${target})
  endif()
endforeach()
if(TARGET hashfusion)
  install(TARGETS hashfusion RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
set(hf_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/hashfusion)
install(EXPORT hashfusionTargets NAMESPACE hashfusion:: DESTINATION ${hf_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hashfusionConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/hashfusionConfig.cmake INSTALL_DESTINATION ${hf_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hashfusionConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/hashfusionConfig.cmake ${PROJECT_BINARY_DIR}/hashfusionConfigVersion.cmake
        DESTINATION ${hf_cmake_dir})

# hf_header_bundle(REL OUT): which precompiled bundle the header check may give header REL (relative to the
# source root): "eigen_geometry" when its include closure (its own #include lines and, recursively, those of the
# project's headers it includes) names <Eigen/Geometry> or <Eigen/Dense>, "eigen_core" when it names another
# Eigen module (each includes Core), else "plain". Includes are read as written, conditional ones too: no public
# header includes Eigen under an #if.
function(hf_header_closure_angles rel out)
  get_property(done GLOBAL PROPERTY hf_closure_done_${rel} SET)
  if(done)
    get_property(angles GLOBAL PROPERTY hf_closure_${rel})
    set(${out} "${angles}" PARENT_SCOPE)
    return()
  endif()
  set_property(GLOBAL PROPERTY hf_closure_done_${rel} TRUE)  # guards include cycles
  set_property(GLOBAL PROPERTY hf_closure_${rel} "")
  file(STRINGS ${PROJECT_SOURCE_DIR}/${rel} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
  set(angles)
  foreach(line IN LISTS lines)
    if(line MATCHES "include[ \t]*<([^>]+)>")
      list(APPEND angles ${CMAKE_MATCH_1})
    elseif(line MATCHES "include[ \t]*\"([^\"]+)\"" AND EXISTS ${PROJECT_SOURCE_DIR}/${CMAKE_MATCH_1})
      hf_header_closure_angles(${CMAKE_MATCH_1} inner)
      list(APPEND angles ${inner})
    endif()
  endforeach()
  list(REMOVE_DUPLICATES angles)
  set_property(GLOBAL PROPERTY hf_closure_${rel} "${angles}")
  set(${out} "${angles}" PARENT_SCOPE)
endfunction()
function(hf_header_bundle rel out)
  hf_header_closure_angles(${rel} angles)
  set(${out} plain PARENT_SCOPE)
  foreach(angle IN LISTS angles)
    if(angle MATCHES "^Eigen/(Geometry|Dense)$")
      set(${out} eigen_geometry PARENT_SCOPE)  # both include Core
      return()
    elseif(angle MATCHES "^Eigen/")
      set(${out} eigen_core PARENT_SCOPE)  # every Eigen module includes Core
    endif()
  endforeach()
endfunction()

if(HF_BUILD_TESTS AND NOT HF_SANITIZE)
  # Each public header alone in a translation unit (the include is all it holds). Most of such a unit's time is
  # parsing Eigen (~1.3 of ~1.9 s here, gcc), so the headers whose own include closure reaches Eigen are compiled
  # with Eigen precompiled: a header is given only third-party headers it includes anyway (hf_header_bundle), so
  # the check still fails for a header that leans on an include it does not make (bench/results/ci.md).
  set(hf_header_tus_eigen_geometry)
  set(hf_header_tus_eigen_core)
  set(hf_header_tus_plain)
  foreach(header IN LISTS hf_public_headers)
    file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${header})
    set(tu ${PROJECT_BINARY_DIR}/header_check/${rel}.cpp)
    file(CONFIGURE OUTPUT ${tu} CONTENT "#include \"${rel}\"\n")
    hf_header_bundle(${rel} bundle)
    list(APPEND hf_header_tus_${bundle} ${tu})
  endforeach()
  add_custom_target(hf_header_check ALL)
  foreach(bundle IN ITEMS eigen_geometry eigen_core plain)
    if(NOT hf_header_tus_${bundle})
      continue()
    endif()
    add_library(hf_header_check_${bundle} OBJECT ${hf_header_tus_${bundle}})
    # One header per translation unit is the point of this check: never batched.
    set_target_properties(hf_header_check_${bundle} PROPERTIES UNITY_BUILD OFF)
    target_link_libraries(hf_header_check_${bundle} PRIVATE ${hf_exported} hf_warnings)
    if(bundle STREQUAL "eigen_geometry")
      target_precompile_headers(hf_header_check_${bundle} PRIVATE <Eigen/Core> <Eigen/Geometry>)
    elseif(bundle STREQUAL "eigen_core")
      target_precompile_headers(hf_header_check_${bundle} PRIVATE <Eigen/Core>)
    endif()
    add_dependencies(hf_header_check hf_header_check_${bundle})
  endforeach()
  # Counted with the tests (a no-op once `all` is built; names the header that fails otherwise).
  add_test(NAME public_headers COMMAND ${CMAKE_COMMAND} --build ${PROJECT_BINARY_DIR} --target hf_header_check)
  set_tests_properties(public_headers PROPERTIES LABELS release_only)

  # An external project built against the installed package (tests/package): install into the build folder,
  # configure, build and run the consumer.
  add_test(NAME package_consumer
           COMMAND ${CMAKE_COMMAND} -DBUILD_DIR=${PROJECT_BINARY_DIR} -DSOURCE_DIR=${PROJECT_SOURCE_DIR}/tests/package
                   -DWORK_DIR=${PROJECT_BINARY_DIR}/package_test -DCXX=${CMAKE_CXX_COMPILER}
                   -DLAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER} -DPYTHON=${Python3_EXECUTABLE}
                   -DPYTHON_DIR=${HF_PYTHON_INSTALL_DIR} -P ${PROJECT_SOURCE_DIR}/cmake/run_package_test.cmake)
  set_tests_properties(package_consumer PROPERTIES LABELS release_only TIMEOUT 300)
endif()
