"""Issue 36: input that cannot be misread. Depth as float32 metres or uint16 with depth_scale (Open3D's convention),
anything else refused naming dtype and shape; a median depth beyond 20 m refused with a hint about units; cameras and
time stamps checked at the call; Python's standard exceptions; datasets indexed and sliced; corrected_trajectory()
as (stamps, poses); make_registration(name, options=)."""
import numpy as np
import pytest

import hashfusion as hf


def _frame_arrays(h=48, w=64, depth_m=1.5):
    depth = np.full((h, w), depth_m, np.float32)
    color = np.zeros((h, w, 3), np.uint8)
    return depth, color


def test_uint16_depth_with_scale_is_metres():
    depth_m, color = _frame_arrays()
    depth_m[::5, ::3] = 0.0
    mm = np.round(depth_m * 1000.0).astype(np.uint16)  # Open3D's default: millimetres
    tum = np.round(depth_m * 5000.0).astype(np.uint16)  # TUM RGB-D's PNGs
    for raw, scale in ((mm, 1000.0), (tum, 5000)):
        f = hf.Frame(raw, color, depth_scale=scale)
        assert f.depth.dtype == np.float32
        # raw / scale in float: exact to float32's rounding of the quotient
        np.testing.assert_allclose(f.depth, raw.astype(np.float64) / scale, rtol=1e-7, atol=0)
        assert (f.depth == 0).sum() == (raw == 0).sum()


def test_depth_dtypes_refused_with_dtype_and_shape():
    depth, color = _frame_arrays()
    for dtype in (np.float64, np.int32, np.uint8, np.int64):
        with pytest.raises(ValueError, match=r"got a %s array of shape \(48, 64\)" % np.dtype(dtype).name):
            hf.Frame(depth.astype(dtype), color)
    with pytest.raises(ValueError, match="needs depth_scale"):  # uint16 without its units: not guessed
        hf.Frame(np.ones((48, 64), np.uint16), color)
    with pytest.raises(ValueError, match="depth_scale applies to uint16"):
        hf.Frame(depth, color, depth_scale=1000.0)
    for bad in (0.0, -1000.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="depth_scale must be a finite number > 0"):
            hf.Frame(np.ones((48, 64), np.uint16), color, depth_scale=bad)
    with pytest.raises(ValueError, match=r"shape \(H, W\)"):
        hf.Frame(np.ones((48, 64, 1), np.float32), color)


def test_implausible_depth_hints_at_units(camera):
    # what the issue saw: TUM's x5000 PNG read the Open3D way and passed as metres (values up to 14069 "m")
    h, w = camera.height, camera.width
    raw = np.full((h, w), 14069, np.uint16)
    color = np.zeros((h, w, 3), np.uint8)
    p = hf.Pipeline(None, camera)
    with pytest.raises(ValueError, match=r"median depth 14069 m is beyond 20 m.*depth_scale=1000.*5000"):
        p.process(raw.astype(np.float32), color, 0.0)
    with pytest.raises(ValueError, match="median depth 2813.8 m"):
        p.process(raw, color, 0.0, depth_scale=5.0)  # a wrong scale is caught too
    assert p.frames_processed == 0
    # the same frame with its units given is accepted: 14069 / 5000 = 2.8138 m
    p.process(raw, color, 0.0, depth_scale=5000)
    assert p.frames_processed == 1
    # the median, not the maximum: a few far pixels (a window) do not trip the check
    depth = np.full((h, w), 2.0, np.float32)
    depth[: h // 4] = 100.0
    hf.Frame(depth, color)
    depth[: h // 2 + 1] = 100.0
    with pytest.raises(ValueError, match="median depth 100 m"):
        hf.Frame(depth, color)


def test_camera_checked_at_construction():
    for kwargs, pattern in (
        (dict(fx=float("nan")), "fx within"),
        (dict(fx=-525.0), "fx within"),
        (dict(fy=1e300), "fy within"),
        (dict(cx=float("inf")), "cx within"),
        (dict(cy=-1e6), "cy within"),
        (dict(width=0), "width and height"),
        (dict(height=20000), "width and height"),
    ):
        with pytest.raises(ValueError, match=pattern):
            hf.Camera(**kwargs)
    c = hf.Camera()
    with pytest.raises(ValueError, match="fx within"):
        c.fx = float("nan")
    assert c.fx == 525.0  # unchanged by the refused assignment
    c.fx = 500.0
    assert c.fx == 500.0


def test_timestamps_checked_at_the_call(synthetic, camera):
    frames = list(synthetic(frames=3))
    p = hf.Pipeline(None, camera)
    f0 = frames[0]
    for bad in (float("nan"), float("inf"), -float("inf")):
        with pytest.raises(ValueError, match="finite time"):
            p.process(f0.depth, f0.color, bad)
        with pytest.raises(ValueError, match="finite time"):
            hf.Frame(f0.depth, f0.color, timestamp=bad)
    p.process(frames[1])
    with pytest.raises(ValueError, match="before the previous frame's"):
        p.process(frames[0])  # decreasing, as a TUM list file may not be
    assert p.frames_processed == 1
    p.process(frames[2])
    p.process(frames[2].depth, frames[2].color, frames[2].timestamp)  # equal is not decreasing
    assert p.frames_processed == 3


def test_standard_exceptions(tmp_path):
    missing = str(tmp_path / "none.ply")
    for call in (lambda: hf.load_mesh(missing), lambda: hf.read_trajectory(missing),
                 lambda: hf.Camera.load(missing), lambda: hf.open_dataset(missing),
                 lambda: hf.ate(missing, missing)):
        with pytest.raises(FileNotFoundError) as e:
            call()
        assert e.value.filename == missing
    # a present but malformed file stays hf.ParseError / hf.Error
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3\n")
    with pytest.raises(hf.ParseError):
        hf.read_trajectory(str(bad))


def test_load_mesh_reads_obj(tmp_path):
    (tmp_path / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    mesh = hf.load_mesh(str(tmp_path / "tri.obj"))
    np.testing.assert_array_equal(mesh.vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2]])


def test_dataset_len_index_slice(synthetic):
    data = synthetic(frames=6)
    assert len(data) == 6
    every = list(synthetic(frames=6))
    # data[i] is the frame iteration yields at i, without moving the iteration
    for i in (0, 3, 5, -1, -6):
        f = data[i]
        g = every[i]
        assert f.index == g.index and f.timestamp == g.timestamp
        np.testing.assert_array_equal(f.depth, g.depth)
        np.testing.assert_array_equal(f.color, g.color)
    assert next(data).index == 0  # indexing did not advance the iteration
    for i in (6, -7):
        with pytest.raises(IndexError, match="out of range"):
            data[i]
    view = data[1:6:2]
    assert len(view) == 3 and [f.index for f in view] == [1, 3, 5]
    assert [f.index for f in view[::-1]] == [5, 3, 1] and view[-1].index == 5
    assert view.camera == data.camera


def test_dataset_index_tum_folder(cli, tmp_path):
    import subprocess
    out = tmp_path / "tum"
    cam = tmp_path / "cam.txt"
    cam.write_text("fx 131.25\nfy 131.25\ncx 79.5\ncy 59.5\nwidth 160\nheight 120\n")
    subprocess.run([cli, "generate", "--frames", "4", "--camera", str(cam), "--out", str(out)], check=True,
                   capture_output=True)
    data = hf.open_dataset(str(out))
    assert len(data) == 4
    frames = list(hf.open_dataset(str(out)))
    np.testing.assert_array_equal(data[2].depth, frames[2].depth)
    assert [f.timestamp for f in data[::3]] == [frames[0].timestamp, frames[3].timestamp]


def test_corrected_trajectory_feeds_ate(synthetic):
    data = synthetic(frames=5)
    p = hf.Pipeline(None, data.camera)
    for f in data:
        p.process(f)
    stamps, poses = p.corrected_trajectory()
    assert stamps.shape == (5,) and poses.shape == (5, 4, 4)
    np.testing.assert_array_equal(stamps, data.ground_truth[0])
    ate = hf.ate(data.ground_truth, p.corrected_trajectory())
    assert ate["pairs"] == 5 and ate["ate_rmse_m"] < 0.01


def test_make_registration_options(synthetic, camera):
    frames = list(synthetic(frames=3))
    defaults = hf.registration_options("icp")
    assert defaults["iterations"] == [10, 5, 4] and "rgb_weight" not in defaults
    few = hf.make_registration("icp", options={"iterations": [1, 1, 1]})
    many = hf.make_registration("icp", options={"iterations": [10, 5, 4]})
    same = hf.make_registration("icp")
    r_few = few.align(frames[2], frames[0], camera)
    r_many = many.align(frames[2], frames[0], camera)
    r_same = same.align(frames[2], frames[0], camera)
    assert r_few.iterations_per_level == [1, 1, 1]
    np.testing.assert_array_equal(r_many.T_ref_cur, r_same.T_ref_cur)  # options = the defaults: same result
    with pytest.raises(hf.Error, match="unknown key 'rgb_weight'"):
        hf.make_registration("icp", options={"rgb_weight": 0.5})
    with pytest.raises(hf.Error, match="options: max_dist_m: expected a number"):
        hf.make_registration("icp", options={"max_dist_m": "far"})
    with pytest.raises(ValueError, match="dict"):
        hf.make_registration("icp", options=[1, 2])


def test_save_and_load_map(synthetic, tmp_path):
    data = synthetic(frames=4)
    p = hf.Pipeline({"volume": {"voxel_m": 0.02}}, data.camera)
    for f in data:
        p.process(f)
    path = str(tmp_path / "room.hfmap")
    p.save(path)
    before = p.extract_mesh()
    q = hf.Pipeline({"volume": {"voxel_m": 0.02}}, data.camera)
    q.load(path)
    after = q.extract_mesh()  # the same volume, bit for bit: the same mesh
    np.testing.assert_array_equal(after.vertices, before.vertices)
    np.testing.assert_array_equal(after.colors, before.colors)
    # continuing: frames of the same sequence track against the loaded model
    states = [q.process(f).state for f in synthetic(frames=4)]
    assert states[0] == "initialised" and all(s in ("tracked", "odometry") for s in states[1:]), states
    with pytest.raises(hf.Error, match="processed frames already"):
        q.load(path)
    with pytest.raises(hf.Error, match="voxels of 0.02"):
        hf.Pipeline({"volume": {"voxel_m": 0.01}}, data.camera).load(path)
    with pytest.raises(FileNotFoundError):
        q.load(str(tmp_path / "none.hfmap"))
