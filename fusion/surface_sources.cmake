list(APPEND HF_FUSION_SOURCES raycast.cpp raycast_sampled.cpp mesh.cpp)
list(APPEND HF_FUSION_SOURCES sparse_render.cpp)  # issue 19: the render for people with fewer rays
