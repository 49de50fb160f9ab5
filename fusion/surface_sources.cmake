list(APPEND HF_FUSION_SOURCES raycast.cpp mesh.cpp)
