"""hashfusion: voxel-hashed TSDF RGB-D SLAM and 3D reconstruction, from Python.

    import hashfusion as hf
    data = hf.open_dataset("synthetic:room", frames=30)       # or a TUM RGB-D / 7-Scenes folder
    pipeline = hf.Pipeline({"registration": "combined"}, data.camera)
    for frame in data:                                        # frame.depth float32 (H, W) metres, frame.color uint8
        result = pipeline.process(frame)                      # result.state, result.T_world_camera (4x4) ...
    mesh = pipeline.extract_mesh()                            # mesh.vertices, mesh.faces, mesh.colors
    o3d_mesh = hf.to_open3d(mesh)                             # with python3-open3d; hf.from_open3d back

Conventions (as in the C++ library): poses are 4x4 float64 arrays named by their frames (T_world_camera maps
camera points into the world), metres everywhere, trajectories are (stamps (N,), poses (N, 4, 4)) pairs or TUM
file paths, configurations are dicts with the keys of report.json's "config". Depth goes in as float32 metres or
as uint16 with depth_scale (units per metre, Open3D's convention: 1000 for millimetres, 5000 for TUM). C++ errors
arrive as hashfusion.Error (ParseError, CapacityError) with the C++ message, bad arguments as ValueError, a
missing file or folder as FileNotFoundError. hf.to_open3d / hf.from_open3d convert Camera, Mesh and PointCloud
to and from Open3D's PinholeCameraIntrinsic, TriangleMesh and PointCloud (python/hashfusion/_open3d.py).
"""
from ._hashfusion import *  # noqa: F401,F403
from ._hashfusion import Dataset, Error, ParseError, CapacityError, __version__  # noqa: F401
from ._open3d import to_open3d, from_open3d  # noqa: F401  (Open3D itself is imported on the first call)


class DatasetView:
    """A lazy slice of a Dataset (data[a:b:s]): frames are read when indexed or iterated, not when sliced."""

    def __init__(self, dataset, indices):
        self._dataset = dataset
        self._indices = indices

    def __len__(self):
        return len(self._indices)

    def __getitem__(self, key):
        picked = self._indices[key]
        if isinstance(key, slice):
            return DatasetView(self._dataset, picked)
        return self._dataset._frame_at(picked)

    def __iter__(self):
        for i in self._indices:
            yield self._dataset._frame_at(i)

    def __repr__(self):
        return "hashfusion.DatasetView(%d frames of %s)" % (len(self), self._dataset.name)

    camera = property(lambda self: self._dataset.camera)


def _dataset_getitem(self, key):
    if isinstance(key, slice):
        return DatasetView(self, range(len(self))[key])
    return self._frame_at(key)


Dataset.__getitem__ = _dataset_getitem
