"""Conversions between hashfusion's and Open3D's types (hf.to_open3d / hf.from_open3d).

    hf.Camera      <-> open3d.camera.PinholeCameraIntrinsic   (width, height, fx, fy, cx, cy; both put pixel
                                                               centres at integer coordinates: copied as they are)
    hf.Mesh        <-> open3d.geometry.TriangleMesh           (vertices, triangles, vertex colours and normals)
    hf.PointCloud  <-> open3d.geometry.PointCloud             (points, colours, normals)

Open3D holds float64 coordinates and colours as float64 in [0, 1]; hashfusion holds float32 and uint8. To Open3D
is exact (float32 widens, c / 255 is read back as c); from Open3D rounds coordinates to float32 and colours to the
nearest of 256 levels (clipped to [0, 1]), so a round trip starting from hashfusion gives back the same arrays.
Absent attributes stay absent (an Open3D mesh without vertex colours becomes an hf.Mesh with colors of shape
(0, 3), and back). Open3D is optional (Debian: python3-open3d) and imported on the first call.
"""
import numpy as np

from ._hashfusion import Camera, Mesh, PointCloud


def _open3d():
    try:
        import open3d
    except ImportError as e:
        raise ImportError("hashfusion's Open3D conversions need the open3d module: install python3-open3d (Debian) "
                          "or `pip install open3d` (" + str(e) + ")") from e
    return open3d


def _colors_to_open3d(colors):
    return colors.astype(np.float64) / 255.0


def _colors_from_open3d(colors):
    return np.rint(np.clip(np.asarray(colors), 0.0, 1.0) * 255.0).astype(np.uint8)


def _rows_or_none(rows, convert):
    """An Open3D attribute vector as a numpy array through convert, or None when it is empty (absent)."""
    return convert(rows) if len(rows) else None


def to_open3d(x):
    """The Open3D object of an hf.Camera, hf.Mesh or hf.PointCloud (new arrays: later changes are not shared)."""
    o3d = _open3d()
    if isinstance(x, Camera):
        return o3d.camera.PinholeCameraIntrinsic(x.width, x.height, x.fx, x.fy, x.cx, x.cy)
    if isinstance(x, Mesh):
        mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(x.vertices.astype(np.float64)),
                                         o3d.utility.Vector3iVector(x.faces.astype(np.int32)))
        if len(x.colors):
            mesh.vertex_colors = o3d.utility.Vector3dVector(_colors_to_open3d(x.colors))
        if len(x.normals):
            mesh.vertex_normals = o3d.utility.Vector3dVector(x.normals.astype(np.float64))
        return mesh
    if isinstance(x, PointCloud):
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(x.points.astype(np.float64)))
        if len(x.colors):
            cloud.colors = o3d.utility.Vector3dVector(_colors_to_open3d(x.colors))
        if len(x.normals):
            cloud.normals = o3d.utility.Vector3dVector(x.normals.astype(np.float64))
        return cloud
    raise TypeError("to_open3d: expected an hf.Camera, hf.Mesh or hf.PointCloud, got " + type(x).__name__)


def from_open3d(x):
    """The hashfusion object of an Open3D PinholeCameraIntrinsic, TriangleMesh or PointCloud (new arrays)."""
    o3d = _open3d()
    if isinstance(x, o3d.camera.PinholeCameraIntrinsic):
        K = np.asarray(x.intrinsic_matrix)
        if K[0, 1] != 0.0:
            raise ValueError("from_open3d: the intrinsic matrix has a skew (%g); hf.Camera has none" % K[0, 1])
        return Camera(fx=K[0, 0], fy=K[1, 1], cx=K[0, 2], cy=K[1, 2], width=x.width, height=x.height)
    to_float32 = lambda rows: np.asarray(rows, dtype=np.float32)  # noqa: E731
    if isinstance(x, o3d.geometry.TriangleMesh):
        return Mesh(to_float32(x.vertices), np.asarray(x.triangles, dtype=np.int32),
                    colors=_rows_or_none(x.vertex_colors, _colors_from_open3d),
                    normals=_rows_or_none(x.vertex_normals, to_float32))
    if isinstance(x, o3d.geometry.PointCloud):
        return PointCloud(to_float32(x.points), colors=_rows_or_none(x.colors, _colors_from_open3d),
                          normals=_rows_or_none(x.normals, to_float32))
    raise TypeError("from_open3d: expected an open3d PinholeCameraIntrinsic, TriangleMesh or PointCloud, got " +
                    type(x).__name__)
