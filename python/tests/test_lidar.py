"""hf.lidar_classify (lidar/built_up_areas.h) on the synthetic settlements with an exact answer
(lidar/synthetic_settlements.h), from point arrays and from a LAS 1.2 file written here, and its bad input."""
import struct

import numpy as np
import pytest

import hashfusion as hf

CLASS_NAMES = ["hamlet", "village", "town", "city"]


@pytest.fixture(scope="module")
def scene():
    return hf.synthetic_settlements(cell_m=1.0, seed=1)


def classify_points(scene, **kw):
    return hf.lidar_classify(points=scene["points"], classification=scene["classification"],
                             cell_m=scene["grid"]["cell_m"], t_s=scene["t_s"], areas=scene["areas"], **kw)


def test_synthetic_settlements_are_classified_exactly(scene):
    r = classify_points(scene)
    assert r["grid"] == scene["grid"]  # grid_over the points' bounding box is the generator's grid
    assert r["classes"].shape == (scene["grid"]["height"], scene["grid"]["width"]) and r["classes"].dtype == np.uint8
    np.testing.assert_array_equal(r["building"], scene["footprints"])
    np.testing.assert_array_equal(r["classes"], scene["classes"])
    assert r["buildings"] == scene["buildings"] == 1 + 9 + 1 + 25 + 49
    # two hamlets of one house, a village of 9, a town of 25, a city of 49: one settlement each (two hamlets)
    stats = r["stats"]
    assert [stats[c]["settlements"] for c in CLASS_NAMES] == [2, 1, 1, 1]
    assert [stats[c]["components"] for c in CLASS_NAMES] == [2, 9, 25, 49]
    for k, name in enumerate(CLASS_NAMES, start=1):
        assert stats[name]["cells"] == int((r["classes"] == k).sum())
    # heights above the sloping ground are k + 1/4 cells (the generator's design), within the ground noise
    h = r["height_m"][r["building"] == 1]
    assert np.all(np.abs(h - np.floor(h) - 0.25) < 0.08)


def test_a_smaller_structuring_element_splits_the_settlements(scene):
    # t^S = 1.5 no longer bridges the houses' gaps (the generator's spacing): no village, town or city remains
    r = hf.lidar_classify(points=scene["points"], classification=scene["classification"], cell_m=1.0, t_s=1.5,
                          areas=scene["areas"])
    assert r["stats"]["city"]["cells"] == 0 and r["stats"]["town"]["cells"] == 0
    assert r["stats"]["hamlet"]["cells"] == int(scene["footprints"].sum())


def write_las(path, xyz, classification, scale=0.001):
    """A LAS 1.2 file, point format 0 (20-byte records), no VLR."""
    q = np.round(xyz / scale).astype(np.int64)
    mins, maxs = q.min(axis=0) * scale, q.max(axis=0) * scale
    header = struct.pack("<4sHH16sBB32s32sHHHIIBHI5I3d3d6d", b"LASF", 0, 0, bytes(16), 1, 2, b"hashfusion test",
                         b"test_lidar.py", 1, 2026, 227, 227, 0, 0, 20, len(q), len(q), 0, 0, 0, 0,
                         scale, scale, scale, 0.0, 0.0, 0.0,
                         maxs[0], mins[0], maxs[1], mins[1], maxs[2], mins[2])
    assert len(header) == 227
    records = np.zeros(len(q), dtype=[("xyz", "<i4", 3), ("intensity", "<u2"), ("flags", "u1"),
                                      ("classification", "u1"), ("angle", "i1"), ("user", "u1"),
                                      ("source", "<u2")])
    records["xyz"] = q
    records["flags"] = 0b001001  # return 1 of 1
    records["classification"] = classification
    with open(path, "wb") as f:
        f.write(header)
        f.write(records.tobytes())


def test_las_file_gives_the_same_classes(scene, tmp_path):
    path = tmp_path / "settlements.las"
    write_las(path, scene["points"], scene["classification"])
    from_file = hf.lidar_classify(las=str(path), cell_m=1.0, t_s=scene["t_s"], areas=scene["areas"])
    np.testing.assert_array_equal(from_file["classes"], scene["classes"])
    assert from_file["stats"] == classify_points(scene)["stats"]
    # a list of files is the union of their points
    both = hf.lidar_classify(las=[str(path), str(path)], cell_m=1.0, t_s=scene["t_s"], areas=scene["areas"])
    np.testing.assert_array_equal(both["classes"], scene["classes"])


def test_lidar_bad_input(scene, tmp_path):
    with pytest.raises(hf.Error, match="missing.las"):
        hf.lidar_classify(las=str(tmp_path / "missing.las"))
    truncated = tmp_path / "truncated.las"
    truncated.write_bytes(b"LASF" + bytes(50))
    with pytest.raises(hf.Error, match="truncated.las"):
        hf.lidar_classify(las=str(truncated))
    with pytest.raises(ValueError, match="either"):
        hf.lidar_classify()
    with pytest.raises(ValueError, match="classification"):
        hf.lidar_classify(points=np.zeros((3, 3)), classification=np.zeros(2))
    with pytest.raises(ValueError, match="finite"):
        hf.lidar_classify(points=np.full((1, 3), np.inf), classification=np.zeros(1))
    with pytest.raises(hf.Error):
        hf.lidar_classify(points=scene["points"], classification=scene["classification"], areas=(3, 2, 1))
    with pytest.raises(hf.Error):
        hf.lidar_classify(points=scene["points"], classification=scene["classification"], cell_m=-1)
