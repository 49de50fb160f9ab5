# Surface side of fusion (raycast, marching cubes), include()d by tests/fusion/CMakeLists.txt.
hf_test(test_raycast SOURCES test_raycast.cpp test_sparse_render.cpp DEPS hf_fusion hf_datasets)
hf_test(test_mesh SOURCES test_mesh.cpp DEPS hf_fusion hf_io)
hf_test(test_fusion_sphere SOURCES test_fusion_sphere.cpp DEPS hf_fusion hf_datasets)
