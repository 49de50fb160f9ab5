"""hf.triangulate (photogrammetry/dlt_triangulation.h): exact synthetic shots recover the point to rounding, the
reprojection errors are the pixel distances, and the degenerate cases come back as a status, never NaN."""
import numpy as np
import pytest

import hashfusion as hf

K = np.array([[500.0, 0, 320], [0, 500.0, 240], [0, 0, 1]])


def look(C, yaw_rad=0.0):
    """P = K [R | -R C] of a camera at C turned by yaw about the y axis (x right, y down, z forward)."""
    c, s = np.cos(yaw_rad), np.sin(yaw_rad)
    R = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    return K @ np.hstack([R, -R @ np.asarray(C, float)[:, None]])


def project(P, X):
    x = P @ np.append(X, 1.0)
    return x[:2] / x[2]


def test_two_cameras_recover_the_point():
    cameras = np.stack([look([0, 0, 0]), look([1.0, 0, 0], -0.1)])
    X = np.array([0.3, -0.2, 5.0])
    pixels = np.stack([project(P, X) for P in cameras])
    t = hf.triangulate(pixels, cameras)
    assert t["status"] == "ok"
    np.testing.assert_allclose(t["X"], X, atol=1e-9)
    assert t["reprojection_error_px"].shape == (2,) and (t["reprojection_error_px"] < 1e-9).all()
    # the angle between the rays at X: atan of the baseline over the depth, to first order
    assert t["max_angle_deg"] == pytest.approx(np.degrees(np.arctan2(1.0, 5.0)), rel=0.05)


def test_many_points_and_their_errors():
    rng = np.random.default_rng(3)
    cameras = np.stack([look([0, 0, 0]), look([1.0, 0, 0], -0.1), look([-1.0, 0.5, 0], 0.1)])
    X = rng.uniform([-1, -1, 4], [1, 1, 8], size=(20, 3))
    pixels = np.stack([[project(P, x) for P in cameras] for x in X])
    t = hf.triangulate(pixels, cameras)
    assert t["status"] == ["ok"] * 20
    np.testing.assert_allclose(t["X"], X, atol=1e-9)
    # one pixel moved by (3, 4): the least-squares point shares the 5 px among the views, each error is the
    # distance from that view's pixel to the reprojection
    noisy = pixels.copy()
    noisy[0, 0] += [3.0, 4.0]
    t = hf.triangulate(noisy, cameras)
    e = t["reprojection_error_px"][0]
    expected = [np.linalg.norm(noisy[0, k] - project(cameras[k], t["X"][0])) for k in range(3)]
    np.testing.assert_allclose(e, expected, atol=1e-9)
    assert 0 < e.max() < 5.0


def test_degenerate_cases_are_a_status():
    P = look([0, 0, 0])
    x = project(P, np.array([0.1, 0.1, 3.0]))
    t = hf.triangulate(np.stack([x, x]), np.stack([P, P]))  # coincident rays
    assert t["status"] == "degenerate" and np.isfinite(t["X"]).all() and (t["X"] == 0).all()
    assert hf.triangulate(x[None], P[None])["status"] == "too_few_views"
    cameras = np.stack([look([0, 0, 0]), look([1.0, 0, 0])])
    behind = np.array([0.3, 0.2, -5.0])  # both cameras see it through their backs
    assert hf.triangulate(np.stack([project(C, behind) for C in cameras]), cameras)["status"] == "behind_camera"


def test_bad_input():
    cameras = np.stack([look([0, 0, 0]), look([1.0, 0, 0])])
    with pytest.raises(ValueError, match="cameras"):
        hf.triangulate(np.zeros((2, 2)), cameras[:, :, :3])
    with pytest.raises(ValueError, match="pixels"):
        hf.triangulate(np.zeros((3, 2)), cameras)
    with pytest.raises(ValueError, match="finite"):
        hf.triangulate(np.full((2, 2), np.nan), cameras)
    singular = cameras.copy()
    singular[1, :, :3] = 0
    with pytest.raises(ValueError, match=r"cameras\[1\]"):
        hf.triangulate(np.zeros((2, 2)), singular)
