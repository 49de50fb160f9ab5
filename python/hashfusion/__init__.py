"""hashfusion: voxel-hashed TSDF RGB-D SLAM and 3D reconstruction, from Python.

    import hashfusion as hf
    data = hf.open_dataset("synthetic:room", frames=30)       # or a TUM RGB-D / 7-Scenes folder
    pipeline = hf.Pipeline({"registration": "combined"}, data.camera)
    for frame in data:                                        # frame.depth float32 (H, W) metres, frame.color uint8
        result = pipeline.process(frame)                      # result.state, result.T_world_camera (4x4) ...
    mesh = pipeline.extract_mesh()                            # mesh.vertices, mesh.faces, mesh.colors

Conventions (as in the C++ library): poses are 4x4 float64 arrays named by their frames (T_world_camera maps
camera points into the world), metres everywhere, trajectories are (stamps (N,), poses (N, 4, 4)) pairs or TUM
file paths, configurations are dicts with the keys of report.json's "config". C++ errors arrive as
hashfusion.Error (ParseError, CapacityError) with the C++ message, bad arguments as ValueError.
"""
from ._hashfusion import *  # noqa: F401,F403
from ._hashfusion import Error, ParseError, CapacityError, __version__  # noqa: F401
