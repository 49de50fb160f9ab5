# Install rules and the CMake package (issues 24, 36), included by CMakeLists.txt once every library folder is added.
#
#   cmake --install build/release --prefix /opt/hashfusion
#   find_package(hashfusion REQUIRED COMPONENTS fusion slam)   # CMAKE_PREFIX_PATH=/opt/hashfusion; no COMPONENTS: all
#   target_link_libraries(app PRIVATE hashfusion::slam)        # #include <hashfusion/slam/pipeline.h>
#
# Every hf_library (global property HF_LIBRARIES) outside bench/ and tests/ is installed and exported as
# hashfusion::NAME (NAME without "hf_": core, io, fusion, registration, slam, ...) and is a component of the package
# of the same NAME. Its folder's headers go under include/hashfusion, with their project includes rewritten at
# install time from "core/se3.h" to <hashfusion/core/se3.h> (cmake/hf_install_headers.cmake), so the installed
# tree is self-consistent and a consumer's own "core/se3.h" cannot shadow ours; consumers get include/ (the folder
# whose child is hashfusion/) on their include path.
#
# Components: hashfusionConfig.cmake finds only the packages (find_dependency) of the requested components and of
# the components they link, transitively: COMPONENTS core io finds Eigen, nlohmann_json, Threads, TBB and OpenCV's
# core/imgproc/imgcodecs, not GDAL, Ceres, OpenCL or PCL. The packages of a library come from its link interface
# through HF_PACKAGE_OF below; a library linking anything else (a target of another package, a plain library path)
# stays out of the package, with what links it, and a configure message naming it (add its package there to
# install it). Each group of libraries that link each other in a cycle (registration <-> registration_opencl)
# shares one export file, hashfusion_GROUPTargets.cmake; the config includes the groups in dependency order. An
# unknown component fails find_package with a message listing the known ones.
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

# Each library's dependencies: hf_internal_LIB (our libraries), hf_packages_LIB (find_dependency arguments, one
# list element each) and hf_opencv_LIB (OpenCV components). A library with an unknown one is dropped.
foreach(lib IN LISTS hf_exported)
  hf_exported_link_items(${lib} items)
  set(unknown)
  set(hf_internal_${lib})
  set(hf_packages_${lib})
  set(hf_opencv_${lib})
  foreach(item IN LISTS items)
    if(item IN_LIST hf_all_libraries)
      list(APPEND hf_internal_${lib} ${item})
      continue()
    elseif(item MATCHES "^opencv_(.*)$")
      list(APPEND hf_opencv_${lib} ${CMAKE_MATCH_1})
      continue()
    endif()
    set(package)
    if(item MATCHES "^([A-Za-z0-9_]+)::")
      set(package "${HF_PACKAGE_OF_${CMAKE_MATCH_1}}")
    endif()
    if(package)
      list(APPEND hf_packages_${lib} "${package}")
    else()
      list(APPEND unknown ${item})
    endif()
  endforeach()
  if(unknown)
    message(STATUS "hf_package: ${lib} is not installed: it links ${unknown}, of no package in HF_PACKAGE_OF_*")
    list(REMOVE_ITEM hf_exported ${lib})
  endif()
endforeach()
# ... and so is every library linking a dropped one (an export cannot name a target that is not installed).
set(hf_dropping TRUE)
while(hf_dropping)
  set(hf_dropping FALSE)
  foreach(lib IN LISTS hf_exported)
    foreach(dep IN LISTS hf_internal_${lib})
      if(NOT dep IN_LIST hf_exported)
        message(STATUS "hf_package: ${lib} is not installed: it links ${dep}, which is not")
        list(REMOVE_ITEM hf_exported ${lib})
        set(hf_dropping TRUE)
        break()
      endif()
    endforeach()
  endforeach()
endwhile()

# hf_closure_LIB: LIB and every library it links, transitively (to a fixed point; there are a dozen).
foreach(lib IN LISTS hf_exported)
  set(hf_closure_${lib} ${lib} ${hf_internal_${lib}})
  list(REMOVE_DUPLICATES hf_closure_${lib})
endforeach()
set(hf_growing TRUE)
while(hf_growing)
  set(hf_growing FALSE)
  foreach(lib IN LISTS hf_exported)
    set(closure ${hf_closure_${lib}})
    foreach(dep IN LISTS hf_closure_${lib})
      list(APPEND closure ${hf_closure_${dep}})
    endforeach()
    list(REMOVE_DUPLICATES closure)
    list(LENGTH closure n_new)
    list(LENGTH hf_closure_${lib} n_old)
    if(n_new GREATER n_old)
      set(hf_closure_${lib} ${closure})
      set(hf_growing TRUE)
    endif()
  endforeach()
endwhile()

# Groups: libraries that reach each other (a link cycle) share one export set, named after the first of them in
# folder order. hf_group_LIB is LIB's group; a group's libraries all have the same closure, and a group that
# links another has a strictly larger one, so sorting by closure size orders the groups by dependency.
set(hf_groups)
set(hf_group_keys)
foreach(lib IN LISTS hf_exported)
  foreach(other IN LISTS hf_exported)
    if(other IN_LIST hf_closure_${lib} AND lib IN_LIST hf_closure_${other})
      string(REGEX REPLACE "^hf_" "" hf_group_${lib} ${other})
      break()
    endif()
  endforeach()
  set(group ${hf_group_${lib}})
  list(APPEND hf_group_libs_${group} ${lib})
  if(NOT group IN_LIST hf_groups)
    list(APPEND hf_groups ${group})
    list(LENGTH hf_closure_${lib} n)
    math(EXPR key "1000 + ${n}")  # fixed width, so the sort below is numeric
    list(APPEND hf_group_keys "${key}:${group}")
  endif()
endforeach()
list(SORT hf_group_keys)
list(TRANSFORM hf_group_keys REPLACE "^[0-9]+:" "" OUTPUT_VARIABLE hf_groups_in_order)

# The package's component table, written into hashfusionConfig.cmake (HF_COMPONENT_TABLE):
#   _hf_components           every component (= exported library) name
#   _hf_group_<component>    its export group
#   _hf_groups               the groups in dependency order
#   _hf_needs_<group>        the groups it needs, itself included
#   _hf_packages_<group>     find_dependency() arguments of its libraries, one list element each
#   _hf_opencv_<group>       OpenCV components its libraries link
set(hf_components)
foreach(lib IN LISTS hf_exported)
  string(REGEX REPLACE "^hf_" "" name ${lib})
  list(APPEND hf_components ${name})
endforeach()
string(REPLACE ";" " " text "${hf_components}")
set(HF_COMPONENT_TABLE "set(_hf_components ${text})\n")
foreach(lib IN LISTS hf_exported)
  string(REGEX REPLACE "^hf_" "" name ${lib})
  string(APPEND HF_COMPONENT_TABLE "set(_hf_group_${name} ${hf_group_${lib}})\n")
endforeach()
string(REPLACE ";" " " text "${hf_groups_in_order}")
string(APPEND HF_COMPONENT_TABLE "set(_hf_groups ${text})\n")
foreach(group IN LISTS hf_groups_in_order)
  set(needs)
  set(packages)
  set(opencv)
  foreach(lib IN LISTS hf_group_libs_${group})
    foreach(dep IN LISTS hf_closure_${lib})
      list(APPEND needs ${hf_group_${dep}})
    endforeach()
    list(APPEND packages ${hf_packages_${lib}})
    list(APPEND opencv ${hf_opencv_${lib}})
  endforeach()
  foreach(var needs packages opencv)
    list(REMOVE_DUPLICATES ${var})
  endforeach()
  string(REPLACE ";" " " needs "${needs}")
  list(TRANSFORM packages PREPEND "\"")
  list(TRANSFORM packages APPEND "\"")
  string(REPLACE ";" " " packages "${packages}")
  string(REPLACE ";" " " opencv "${opencv}")
  string(APPEND HF_COMPONENT_TABLE "set(_hf_needs_${group} ${needs})\n"
                                   "set(_hf_packages_${group} ${packages})\n"
                                   "set(_hf_opencv_${group} ${opencv})\n")
endforeach()

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
# The headers are copied by a script at install time (their includes rewritten to <hashfusion/...>), from this
# list of paths relative to the source root.
set(hf_header_list)
foreach(header IN LISTS hf_public_headers)
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${header})
  list(APPEND hf_header_list ${rel})
endforeach()
list(JOIN hf_header_list "\n" text)
file(CONFIGURE OUTPUT ${PROJECT_BINARY_DIR}/hf_installed_headers.txt CONTENT "${text}\n")
install(CODE "
  set(HF_SOURCE_DIR [==[${PROJECT_SOURCE_DIR}]==])
  set(HF_HEADER_LIST [==[${PROJECT_BINARY_DIR}/hf_installed_headers.txt]==])
  set(HF_STAGING_DIR [==[${PROJECT_BINARY_DIR}/hf_install_headers]==])
  set(HF_INCLUDE_DIR [==[${CMAKE_INSTALL_INCLUDEDIR}]==])
  include([==[${PROJECT_SOURCE_DIR}/cmake/hf_install_headers.cmake]==])")
set(hf_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/hashfusion)
foreach(group IN LISTS hf_groups_in_order)
  install(TARGETS ${hf_group_libs_${group}} EXPORT hashfusion_${group}Targets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(EXPORT hashfusion_${group}Targets NAMESPACE hashfusion:: DESTINATION ${hf_cmake_dir})
endforeach()
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
