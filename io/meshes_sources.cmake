# Mesh and point-cloud files of hf_io (include()d by io/CMakeLists.txt before hf_io is defined): PLY and OBJ.
# PCD lives in hf_io_pcl (io/pcl.cmake) so only its users compile and link PCL.
list(APPEND HF_IO_SOURCES ply.cpp obj.cpp mesh_file.cpp)  # mesh_file: either, by extension
list(APPEND HF_IO_DEPS Eigen3::Eigen)
