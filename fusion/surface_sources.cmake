list(APPEND HF_FUSION_SOURCES raycast.cpp raycast_sampled.cpp mesh.cpp)
