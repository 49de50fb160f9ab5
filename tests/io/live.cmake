# Tests of live capture (hf_io_live; include()d by tests/io/CMakeLists.txt). None needs a device: the queue runs on
# a scripted device, pixel formats on synthetic buffers, OpenNI2 on its own Dummy driver and file driver; a test
# that would need real hardware skips with a message.
if(TARGET hf_io_live)
  hf_test(test_io_live_source SOURCES test_live_source.cpp DEPS hf_io_live)
endif()
if(TARGET hf_io_live)
  hf_test(test_io_pixel_formats SOURCES test_pixel_formats.cpp DEPS hf_io_live opencv_core opencv_imgcodecs)
  if(TARGET PkgConfig::HF_LIBCAMERA)
    target_link_libraries(test_io_pixel_formats PRIVATE PkgConfig::HF_LIBCAMERA)
  endif()
endif()
