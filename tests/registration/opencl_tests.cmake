# Tests of registration/opencl (include()d by tests/registration/CMakeLists.txt). Each test skips with a message
# when no OpenCL platform is installed.
if(TARGET hf_registration_opencl)
  hf_test(test_registration_opencl SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_opencl_backend.cpp
          DEPS hf_registration hf_registration_opencl hf_datasets LABELS registration)
  # The same binary with the ICD loader looking in an empty folder: no platform, so make_backend("opencl") must
  # fail with the documented message (NoPlatform.*).
  add_test(NAME registration_opencl_no_platform
           COMMAND $<TARGET_FILE:test_registration_opencl> --gtest_filter=NoPlatform.*)
  set_tests_properties(registration_opencl_no_platform PROPERTIES
    LABELS registration
    ENVIRONMENT "OCL_ICD_VENDORS=${CMAKE_CURRENT_BINARY_DIR}/no_opencl_vendors;OCL_ICD_FILENAMES="
    FIXTURES_REQUIRED hf_no_opencl_vendors)
  add_test(NAME registration_opencl_no_platform_setup
           COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_CURRENT_BINARY_DIR}/no_opencl_vendors)
  set_tests_properties(registration_opencl_no_platform_setup PROPERTIES FIXTURES_SETUP hf_no_opencl_vendors)
endif()
