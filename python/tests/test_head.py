"""Head-model bindings (hf.curvature, hf.head_features): the evaluations on a tessellated sphere against the
analytic 1/r and 1/r^2, and the whole method on a head-like bumped ellipsoid (tests/head's synthetic shape)."""
import numpy as np
import pytest

import hashfusion as hf


def icosphere(radius, levels):
    """Icosahedron refined `levels` times (each edge halved), vertices pushed onto the sphere; outward winding."""
    t = (1.0 + 5.0 ** 0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(levels):
        mid, faces = {}, []

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                mid[key] = len(v) - 1
            return mid[key]

        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return (np.array(v) * radius).astype(np.float32), np.array(f, dtype=np.int32)


def test_discrete_curvature_of_a_sphere():
    # tests/head/test_curvature.cpp: on the level-3 icosphere the discrete H is exact to float rounding (< 5e-4
    # relative) and K within 1.1e-2 relative (2x the measured 5.5e-3).
    r = 2.0
    vertices, faces = icosphere(r, 3)
    c = hf.curvature(vertices, faces)
    assert set(c) == {"mean", "gaussian", "k_max", "k_min", "valid"}
    assert c["mean"].shape == (len(vertices),) and c["valid"].dtype == bool and c["valid"].all()
    np.testing.assert_allclose(c["mean"] * r, 1.0, atol=5e-4)
    np.testing.assert_allclose(c["gaussian"] * r * r, 1.0, atol=1.1e-2)
    # eq. 5 with the H^2 < K guard: k_max >= k_min, both near 1/r (K's error moves them by sqrt of it)
    assert (c["k_max"] >= c["k_min"]).all()
    np.testing.assert_allclose(c["k_max"] * r, 1.0, atol=0.06)


def test_mls_curvature_of_a_sphere():
    # the C++ suite's bound on the level-4 icosphere: H within 1 %, K within 2 %
    r = 0.5
    vertices, faces = icosphere(r, 4)
    c = hf.curvature(vertices, faces, method="mls")
    assert c["valid"].all()
    np.testing.assert_allclose(c["mean"] * r, 1.0, atol=0.01)
    np.testing.assert_allclose(c["gaussian"] * r * r, 1.0, atol=0.02)


def bumped_ellipsoid():
    """tests/head/test_head_features.cpp's head-like shape: a nose bump at +y, the back flattened, x = 0 the
    mirror plane, z up."""
    vertices, faces = icosphere(1.0, 4)
    v = vertices.astype(np.float64)
    unit_y = v[:, 1] / np.linalg.norm(v, axis=1)
    v[:, 0] *= 0.8
    v[:, 2] *= 1.2
    v[v[:, 1] < 0, 1] *= 0.7
    angle = np.arccos(np.clip(unit_y, -1.0, 1.0))
    bump = np.where(angle < 0.35, 1.0 + 0.25 * np.cos(angle / 0.35 * np.pi / 2) ** 2, 1.0)
    return (v * bump[:, None]).astype(np.float32), faces


def test_head_features_on_a_head_like_mesh():
    vertices, faces = bumped_ellipsoid()
    r = hf.head_features(vertices, faces)
    n = len(vertices)
    for key in ("mean", "gaussian", "k_max", "k_min"):
        assert r["discrete"][key].shape == (n,) and np.isfinite(r["discrete"][key]).all()
    assert r["features"].shape == (n,) and r["features"].dtype == bool
    assert r["area"].shape == (n,) and r["area"].max() <= 6
    assert np.isfinite(r["evaluation_percent"]).all() and np.isfinite(r["laplace"]).all()
    # the nose tip is the bump's apex: the vertex farthest along +y
    assert r["nose_tip_vertex"] == int(np.argmax(vertices[:, 1]))
    a, b = r["threshold"]
    assert -100 <= a <= b == 100  # default: the evaluation's average .. 100
    assert r["features"].any()
    for cp in r["control_points"]:
        assert set(cp) == {"name", "vertex", "position"}
        assert 0 <= cp["vertex"] < n
        np.testing.assert_array_equal(cp["position"], vertices[cp["vertex"]])
    tips = [cp for cp in r["control_points"] if cp["name"] == "nose.tip"]
    assert len(tips) == 1 and tips[0]["vertex"] == r["nose_tip_vertex"]


def test_head_bad_input():
    vertices, faces = icosphere(1.0, 1)
    with pytest.raises(hf.Error, match="mls"):
        hf.curvature(vertices, faces, method="MLS")
    with pytest.raises(ValueError, match="faces"):
        hf.curvature(vertices, faces[:, :2])
    with pytest.raises(hf.Error):
        hf.head_features(vertices, faces)  # 42 vertices: too few for the head frame
    big, big_faces = icosphere(1.0, 3)
    with pytest.raises(hf.Error, match="threshold"):
        hf.head_features(big, big_faces, threshold="10,5")
