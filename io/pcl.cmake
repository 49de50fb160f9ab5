# hf_io_pcl: PCD point clouds through PCL (include()d by io/CMakeLists.txt after hf_io is defined). PCL is slow to
# compile and heavy to link, so it stays behind this one small library; io/pcd.h itself mentions hf types only.
# VTK is only needed for pcl_visualization; not looking for it keeps configure fast (shared/setup/NOTES.md).
set(CMAKE_DISABLE_FIND_PACKAGE_VTK ON)
find_package(PCL 1.13 REQUIRED COMPONENTS common io)
unset(CMAKE_DISABLE_FIND_PACKAGE_VTK)
hf_library(hf_io_pcl SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/pcd.cpp DEPS hf_io)
target_include_directories(hf_io_pcl SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
target_compile_definitions(hf_io_pcl PRIVATE ${PCL_DEFINITIONS})
target_link_libraries(hf_io_pcl PRIVATE ${PCL_LIBRARIES})
