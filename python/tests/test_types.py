"""Round trips of every value type between Python and C++: SE3 (4x4), cameras, frames, meshes, trajectories,
configs, results."""
import pickle

import numpy as np
import pytest

import hashfusion as hf


def random_pose(rng):
    xi = np.concatenate([rng.uniform(-1.0, 1.0, 3), rng.uniform(-2.0, 2.0, 3)])
    return hf.se3_exp(xi), xi


def test_se3_exp_log_round_trip():
    rng = np.random.default_rng(1)
    for _ in range(50):
        T, xi = random_pose(rng)
        assert T.shape == (4, 4) and T.dtype == np.float64
        # exp is exact to rounding: a rotation (R^T R = I) with the bottom row (0 0 0 1)
        np.testing.assert_allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-14)
        np.testing.assert_array_equal(T[3], [0, 0, 0, 1])
        # |omega| < pi, so log inverts exp (to the conditioning of the angle, ~1e-15 / sin(|omega|/2))
        np.testing.assert_allclose(hf.se3_log(T), xi, atol=1e-12)
        np.testing.assert_allclose(hf.se3_normalize(T), T, atol=1e-15)


def test_se3_input_is_checked():
    T = np.eye(4)
    for bad, what in [(np.eye(3), "4x4"), (np.ones((4, 4)), "bottom row"),
                      (np.diag([1.0, 1.0, -1.0, 1.0]), "rotation"), (np.full((4, 4), np.nan), "non-finite")]:
        with pytest.raises(ValueError, match=what):
            hf.se3_log(bad)
    with pytest.raises(ValueError, match="4x4"):
        hf.se3_log("not a matrix")
    # a list of lists is an array-like
    np.testing.assert_array_equal(hf.se3_normalize(T.tolist()), T)


def test_camera_round_trips(tmp_path):
    c = hf.Camera(fx=500.5, fy=501.25, cx=320.125, cy=241.0, width=640, height=480)
    assert pickle.loads(pickle.dumps(c)) == c
    c.save(str(tmp_path / "camera.json"))
    assert hf.Camera.load(str(tmp_path / "camera.json")) == c
    np.testing.assert_array_equal(c.K, [[500.5, 0, 320.125], [0, 501.25, 241.0], [0, 0, 1]])
    ros = hf.Camera.preset("ros")
    # pyramid level 1: c_1 = (c + 0.5) / 2 - 0.5, f_1 = f / 2, size halved (core/camera.h)
    half = ros.scaled(1)
    assert (half.fx, half.cx, half.width, half.height) == (262.5, 159.5, 320, 240)
    assert "ros" in hf.Camera.preset_names()
    with pytest.raises(hf.Error, match="known"):
        hf.Camera.preset("no-such-camera")


def test_frame_arrays_round_trip_and_are_views():
    rng = np.random.default_rng(2)
    depth = rng.uniform(0.5, 4.0, (48, 64)).astype(np.float32)
    depth[::7, ::5] = 0.0
    color = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    pose = hf.se3_exp([0.1, -0.2, 0.3, 1.0, 2.0, 3.0])
    f = hf.Frame(depth, color, timestamp=12.5, T_world_camera_gt=pose)
    np.testing.assert_array_equal(f.depth, depth)
    np.testing.assert_array_equal(f.color, color)
    assert f.depth.dtype == np.float32 and f.color.dtype == np.uint8 and f.color.shape == (48, 64, 3)
    assert f.timestamp == 12.5
    np.testing.assert_allclose(f.T_world_camera_gt, pose, atol=1e-15)
    # the arrays are views of the frame's own images (no copy per access), kept alive by the array
    a = f.depth
    assert not a.flags.owndata and a.base is not None
    del f
    np.testing.assert_array_equal(a, depth)
    # non-contiguous and float64 inputs are converted
    # float64 depth is refused (issue 36: nothing is converted without a word), naming dtype and shape
    with pytest.raises(ValueError, match=r"float64 array of shape \(48, 64\)"):
        hf.Frame(depth.astype(np.float64), color)
    g = hf.Frame(depth[:, :], np.ascontiguousarray(color[:, :, :]))
    np.testing.assert_array_equal(g.depth, depth)
    assert g.T_world_camera_gt is None


def test_mesh_round_trip(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.int32)
    colors = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]], dtype=np.uint8)
    m = hf.Mesh(vertices, faces, colors=colors)
    np.testing.assert_array_equal(m.vertices, vertices)
    np.testing.assert_array_equal(m.faces, faces)
    np.testing.assert_array_equal(m.colors, colors)
    assert m.normals.shape == (0, 3)
    m.save(str(tmp_path / "tet.ply"))
    back = hf.load_mesh(str(tmp_path / "tet.ply"))
    np.testing.assert_array_equal(back.vertices, vertices)
    np.testing.assert_array_equal(back.faces, faces)
    np.testing.assert_array_equal(back.colors, colors)
    with pytest.raises(hf.Error, match="outside"):
        hf.Mesh(vertices, faces + 1)


def test_trajectory_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    stamps = np.cumsum(rng.uniform(0.01, 0.05, 20)) + 1e9
    poses = np.stack([random_pose(rng)[0] for _ in stamps])
    path = str(tmp_path / "t.txt")
    hf.write_trajectory(path, (stamps, poses))
    s, p = hf.read_trajectory(path)
    # 17 significant digits in the file: stamps exact, poses through a unit quaternion (~1e-16 relative)
    np.testing.assert_array_equal(s, stamps)
    np.testing.assert_allclose(p, poses, atol=1e-14)


def test_config_round_trip(camera):
    defaults = hf.default_config()
    assert defaults["registration"] == "combined" and "volume" in defaults
    p = hf.Pipeline(defaults, camera)
    assert p.config == defaults
    # another method: its own knobs replace combined's (registration_options holds the method's keys only)
    changed = {k: v for k, v in defaults.items() if k != "registration_options"}
    changed.update(registration="icp", tracking_level=0)
    changed["volume"] = dict(defaults["volume"], voxel_m=0.02)
    got = hf.Pipeline(changed, camera).config
    assert got["registration"] == "icp" and got["tracking_level"] == 0 and got["volume"]["voxel_m"] == 0.02
    assert "rgb_weight" not in got["registration_options"] and "rgb_weight" in defaults["registration_options"]
    with pytest.raises(hf.Error, match="unknown key"):  # combined's knobs under icp
        hf.Pipeline(dict(defaults, registration="icp"), camera)
    # a partial dict overrides the defaults, like a config file
    assert hf.Pipeline({"tracking_level": 2}, camera).config == dict(defaults, tracking_level=2)


def test_frame_result_fields(synthetic):
    data = synthetic(frames=3)
    p = hf.Pipeline(None, data.camera)
    results = [p.process(f) for f in data]
    assert [r.state for r in results[:1]] == ["initialised"]
    r = results[-1]
    assert r.state == "tracked" and r.pose_valid and r.integrated
    assert r.T_world_camera.shape == (4, 4)
    reg = r.registration
    assert reg.status in ("good", "poor") and reg.usable()
    assert reg.information.shape == (6, 6)
    # the information matrix J^T W J is symmetric positive semi-definite
    np.testing.assert_allclose(reg.information, reg.information.T, rtol=1e-12, atol=1e-9)
    assert np.linalg.eigvalsh(reg.information).min() > -1e-6 * np.abs(reg.information).max()
    assert 0.0 < reg.inlier_ratio <= 1.0 and set(r.ms) >= {"preprocess", "track", "integrate", "total"}
