"""Bad input becomes a Python exception carrying the C++ message: hf.Error (ParseError, CapacityError) for what
the library refuses, ValueError for arguments the bindings cannot convert."""
import numpy as np
import pytest

import hashfusion as hf


def test_exception_hierarchy():
    assert issubclass(hf.Error, RuntimeError)
    assert issubclass(hf.ParseError, hf.Error) and issubclass(hf.CapacityError, hf.Error)


def test_bad_config(camera):
    with pytest.raises(hf.Error, match="no_such_key"):
        hf.Pipeline({"no_such_key": 1}, camera)
    with pytest.raises(hf.Error, match="voxel_m"):
        hf.Pipeline({"volume": {"voxel_m": -1.0}}, camera)
    with pytest.raises(hf.Error, match="registration"):
        hf.Pipeline({"registration": "no-such-method"}, camera)
    with pytest.raises(ValueError, match="config.volume"):
        hf.Pipeline({"volume": object()}, camera)


def test_bad_dataset(tmp_path):
    # a missing folder is Python's FileNotFoundError (issue 36), naming the path
    with pytest.raises(FileNotFoundError, match=str(tmp_path / "missing")) as missing:
        hf.open_dataset(str(tmp_path / "missing"))
    assert missing.value.filename == str(tmp_path / "missing")
    with pytest.raises(hf.Error, match="preset"):
        hf.open_dataset("synthetic:no-such-preset")
    # a TUM folder whose list file is malformed: ParseError naming file and line
    (tmp_path / "tum").mkdir()
    (tmp_path / "tum" / "rgb.txt").write_text("# colour\n1.0 rgb/1.png extra words here\nnot a number\n")
    (tmp_path / "tum" / "depth.txt").write_text("1.0 depth/1.png\n")
    with pytest.raises(hf.Error, match="rgb.txt"):
        hf.open_dataset(str(tmp_path / "tum"))


def test_bad_trajectory(tmp_path):
    path = tmp_path / "t.txt"
    path.write_text("1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n")
    with pytest.raises(hf.ParseError, match=r"t\.txt:2"):
        hf.read_trajectory(str(path))
    with pytest.raises(ValueError, match="increase"):
        hf.ate((np.array([1.0, 1.0]), np.stack([np.eye(4)] * 2)), (np.array([1.0]), np.eye(4)[None]))
    with pytest.raises(ValueError, match="shape"):
        hf.ate((np.array([1.0, 2.0]), np.eye(4)), str(path))
    few = (np.array([1.0, 2.0]), np.stack([np.eye(4)] * 2))
    with pytest.raises(hf.Error, match="at least 3"):
        hf.ate(few, few)


def test_bad_frames(camera):
    p = hf.Pipeline(None, camera)
    h, w = camera.height, camera.width
    color = np.zeros((h, w, 3), np.uint8)
    with pytest.raises(hf.Error, match="camera is 320x240"):
        p.process(np.ones((h + 1, w), np.float32), np.zeros((h + 1, w, 3), np.uint8), 0.0)
    depth = np.ones((h, w), np.float32)
    depth[3, 5] = np.nan
    with pytest.raises(ValueError, match=r"pixel \(5, 3\)"):
        p.process(depth, color, 0.0)
    with pytest.raises(ValueError, match="uint8"):
        p.process(np.ones((h, w), np.float32), color.astype(np.float32), 0.0)
    with pytest.raises(ValueError, match=r"\(H, W, 3\)"):
        p.process(np.ones((h, w), np.float32), color[:, :, 0], 0.0)
    with pytest.raises(ValueError, match="T_world_camera"):
        p.render(np.zeros((4, 4)))
    assert p.frames_processed == 0


def test_capacity_error(camera):
    data = hf.open_dataset("synthetic:room", camera=camera, frames=2)
    p = hf.Pipeline({"volume": {"capacity_blocks": 4}}, data.camera)
    with pytest.raises(hf.CapacityError, match="capacity"):
        for f in data:
            p.process(f)
