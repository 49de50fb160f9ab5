"""hf.PointCloud, Pipeline.extract_cloud and the Open3D conversions (hf.to_open3d / hf.from_open3d, issue 36).

The conversions are checked where python3-open3d is installed (skipped, saying so, elsewhere): hashfusion -> Open3D
-> hashfusion gives back the same arrays bit for bit (float32 widens exactly to float64, uint8 c / 255 reads back
as c); Open3D -> hashfusion rounds coordinates to float32 (relative error <= 2^-24, half a float32 ulp) and colours
to the nearest 1/255 (error <= 0.5 / 255); and Open3D reads the PLY hashfusion writes as the same geometry as
to_open3d gives.
"""
import sys

import numpy as np
import pytest

import hashfusion as hf

FLOAT32_RTOL = 2.0 ** -24  # float64 -> float32 rounding, relative
COLOR_ATOL = 0.5 / 255.0   # [0, 1] -> uint8 rounding


@pytest.fixture(scope="module")
def fused_mesh():
    """A fused mesh with colours and normals (synthetic room, 4 frames at 320x240)."""
    camera = hf.Camera.preset("ros").scaled(1)
    data = hf.open_dataset("synthetic:room", camera=camera, frames=4)
    p = hf.Pipeline({"volume": {"voxel_m": 0.04}}, data.camera)
    for f in data:
        p.process(f)
    return p.extract_mesh(), p.extract_cloud()


# hf.PointCloud itself (no Open3D needed)

def test_point_cloud_arrays_and_file(tmp_path):
    rng = np.random.default_rng(1)
    points = rng.normal(size=(50, 3)).astype(np.float32)
    colors = rng.integers(0, 256, size=(50, 3), dtype=np.uint8)
    normals = rng.normal(size=(50, 3)).astype(np.float32)
    cloud = hf.PointCloud(points, colors=colors, normals=normals)
    assert len(cloud) == 50 and "50 points, colors, normals" in repr(cloud)
    np.testing.assert_array_equal(cloud.points, points)
    np.testing.assert_array_equal(cloud.colors, colors)
    np.testing.assert_array_equal(cloud.normals, normals)
    assert cloud.points.dtype == np.float32 and cloud.colors.dtype == np.uint8
    path = str(tmp_path / "cloud.ply")
    cloud.save(path)
    back = hf.load_point_cloud(path)  # binary PLY of float32 / uint8: exact
    np.testing.assert_array_equal(back.points, points)
    np.testing.assert_array_equal(back.colors, colors)
    np.testing.assert_array_equal(back.normals, normals)
    bare = hf.PointCloud(points)
    assert bare.colors.shape == (0, 3) and bare.normals.shape == (0, 3)


def test_point_cloud_refuses_bad_arrays(tmp_path):
    with pytest.raises(ValueError, match=r"PointCloud: points must be an \(N, 3\) array"):
        hf.PointCloud(np.zeros((4, 2), np.float32))
    with pytest.raises(ValueError, match="PointCloud: colors must be a uint8"):
        hf.PointCloud(np.zeros((4, 3), np.float32), colors=np.zeros((4, 3), np.float64))
    with pytest.raises(hf.Error, match="point cloud"):  # 3 colours for 4 points
        hf.PointCloud(np.zeros((4, 3), np.float32), colors=np.zeros((3, 3), np.uint8))
    with pytest.raises(hf.Error, match="non-finite"):
        hf.PointCloud(np.array([[0, 0, np.nan]], np.float32))
    with pytest.raises(FileNotFoundError, match="load_point_cloud"):
        hf.load_point_cloud(str(tmp_path / "none.ply"))


def test_extract_cloud_is_the_mesh_surface(fused_mesh):
    mesh, cloud = fused_mesh
    assert len(cloud) == len(mesh.vertices) > 1000
    np.testing.assert_array_equal(cloud.points, mesh.vertices)
    np.testing.assert_array_equal(cloud.colors, mesh.colors)
    np.testing.assert_array_equal(cloud.normals, mesh.normals)
    assert len(cloud.colors) == len(cloud) and len(cloud.normals) == len(cloud)


def test_without_open3d_the_error_names_the_package(monkeypatch):
    monkeypatch.setitem(sys.modules, "open3d", None)  # `import open3d` now raises ImportError
    with pytest.raises(ImportError, match="python3-open3d"):
        hf.to_open3d(hf.Camera())
    with pytest.raises(ImportError, match="python3-open3d"):
        hf.from_open3d(object())


# The conversions (python3-open3d)

@pytest.fixture(scope="module")
def o3d():
    try:
        import open3d
    except ImportError as e:
        pytest.skip("open3d is not importable (install python3-open3d to run the Open3D conversion tests): %s" % e)
    return open3d


def test_camera_round_trip(o3d):
    camera = hf.Camera(fx=517.3, fy=516.5, cx=318.6, cy=255.3, width=640, height=480)
    intrinsic = hf.to_open3d(camera)
    assert isinstance(intrinsic, o3d.camera.PinholeCameraIntrinsic)
    assert (intrinsic.width, intrinsic.height) == (640, 480)
    np.testing.assert_array_equal(np.asarray(intrinsic.intrinsic_matrix), camera.K)
    assert hf.from_open3d(intrinsic) == camera
    prime = o3d.camera.PinholeCameraIntrinsic(o3d.camera.PinholeCameraIntrinsicParameters.PrimeSenseDefault)
    back = hf.from_open3d(prime)
    assert (back.fx, back.fy, back.cx, back.cy, back.width, back.height) == (525.0, 525.0, 319.5, 239.5, 640, 480)


def test_mesh_round_trip_is_exact(o3d, fused_mesh):
    mesh, _ = fused_mesh
    m = hf.to_open3d(mesh)
    assert isinstance(m, o3d.geometry.TriangleMesh)
    np.testing.assert_array_equal(np.asarray(m.vertices), mesh.vertices.astype(np.float64))
    np.testing.assert_array_equal(np.asarray(m.triangles), mesh.faces)
    np.testing.assert_array_equal(np.asarray(m.vertex_colors), mesh.colors / 255.0)
    np.testing.assert_array_equal(np.asarray(m.vertex_normals), mesh.normals.astype(np.float64))
    back = hf.from_open3d(m)
    for name in ("vertices", "faces", "colors", "normals"):
        np.testing.assert_array_equal(getattr(back, name), getattr(mesh, name), err_msg=name)
        assert getattr(back, name).dtype == getattr(mesh, name).dtype, name


def test_mesh_from_open3d(o3d):
    box = o3d.geometry.TriangleMesh.create_box(0.3, 0.2, 0.1).translate((1.0 / 3.0, 0.1, -2.0))
    box.compute_vertex_normals()
    colors = np.random.default_rng(2).uniform(0.0, 1.0, size=(len(box.vertices), 3))
    box.vertex_colors = o3d.utility.Vector3dVector(colors)
    mesh = hf.from_open3d(box)
    np.testing.assert_allclose(mesh.vertices, np.asarray(box.vertices), rtol=FLOAT32_RTOL, atol=0)
    np.testing.assert_array_equal(mesh.faces, np.asarray(box.triangles))
    np.testing.assert_allclose(mesh.normals, np.asarray(box.vertex_normals), rtol=FLOAT32_RTOL, atol=0)
    np.testing.assert_allclose(mesh.colors / 255.0, colors, rtol=0, atol=COLOR_ATOL)
    # without colours or normals: absent on both sides
    bare = hf.from_open3d(o3d.geometry.TriangleMesh.create_tetrahedron())
    assert bare.colors.shape == (0, 3) and bare.normals.shape == (0, 3) and len(bare.faces) == 4
    again = hf.to_open3d(bare)
    assert not again.has_vertex_colors() and not again.has_vertex_normals()


def test_open3d_reads_our_ply_as_to_open3d_gives(o3d, fused_mesh, tmp_path):
    mesh, cloud = fused_mesh
    path = str(tmp_path / "mesh.ply")
    mesh.save(path)
    read = o3d.io.read_triangle_mesh(path)
    converted = hf.to_open3d(mesh)
    np.testing.assert_array_equal(np.asarray(read.vertices), np.asarray(converted.vertices))
    np.testing.assert_array_equal(np.asarray(read.triangles), np.asarray(converted.triangles))
    np.testing.assert_array_equal(np.asarray(read.vertex_colors), np.asarray(converted.vertex_colors))
    path = str(tmp_path / "cloud.ply")
    cloud.save(path)
    read = o3d.io.read_point_cloud(path)
    np.testing.assert_array_equal(np.asarray(read.points), np.asarray(hf.to_open3d(cloud).points))


def test_point_cloud_round_trips(o3d, fused_mesh):
    _, cloud = fused_mesh
    pc = hf.to_open3d(cloud)
    assert isinstance(pc, o3d.geometry.PointCloud) and len(pc.points) == len(cloud)
    back = hf.from_open3d(pc)
    for name in ("points", "colors", "normals"):
        np.testing.assert_array_equal(getattr(back, name), getattr(cloud, name), err_msg=name)
    # from Open3D: float64 points to float32, colours to uint8
    rng = np.random.default_rng(3)
    theirs = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(rng.normal(size=(100, 3))))
    theirs.colors = o3d.utility.Vector3dVector(rng.uniform(size=(100, 3)))
    ours = hf.from_open3d(theirs)
    np.testing.assert_allclose(ours.points, np.asarray(theirs.points), rtol=FLOAT32_RTOL, atol=0)
    np.testing.assert_allclose(ours.colors / 255.0, np.asarray(theirs.colors), rtol=0, atol=COLOR_ATOL)
    assert ours.normals.shape == (0, 3)


def test_conversion_refuses_other_types(o3d):
    with pytest.raises(TypeError, match="to_open3d: expected"):
        hf.to_open3d(np.zeros((3, 3)))
    with pytest.raises(TypeError, match="from_open3d: expected"):
        hf.from_open3d(o3d.geometry.LineSet())
