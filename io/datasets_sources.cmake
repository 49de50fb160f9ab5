# Dataset readers of hf_io (include()d by io/CMakeLists.txt): image loading/writing, the FrameSource interface,
# TUM RGB-D and 7-Scenes folders, open_dataset auto-detection and the prefetching wrapper.
list(APPEND HF_IO_SOURCES image_io.cpp tum_dataset.cpp seven_scenes.cpp dataset.cpp prefetch.cpp)
list(APPEND HF_IO_DEPS opencv_core opencv_imgcodecs Threads::Threads)
