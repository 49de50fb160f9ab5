# Tests of the mesh and point-cloud files (include()d by tests/io/CMakeLists.txt).
hf_test(test_ply SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_ply.cpp DEPS hf_io)
hf_test(test_obj SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_obj.cpp DEPS hf_io)
if(TARGET hf_io_pcl)
  hf_test(test_pcd SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_pcd.cpp DEPS hf_io_pcl)
endif()
hf_fuzzer(fuzz_ply SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_ply.cpp DEPS hf_io)
hf_fuzzer(fuzz_obj SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_obj.cpp DEPS hf_io)
