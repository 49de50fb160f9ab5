"""No leaks across 1000 calls of each binding that allocates: the process's resident memory stays within a bound
far below what one leaked output per call would add, and Python-side allocations (tracemalloc) do not grow."""
import gc
import resource
import tracemalloc

import numpy as np
import pytest

import hashfusion as hf

CALLS = 1000


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize()


def grows(call, per_call_bytes):
    """Resident growth over CALLS calls after a warm-up, against a bound of 5 % of a leak of per_call_bytes each."""
    for _ in range(20):
        call()
    gc.collect()
    before = rss_bytes()
    for _ in range(CALLS):
        call()
    gc.collect()
    growth = rss_bytes() - before
    return growth, 0.05 * CALLS * per_call_bytes


@pytest.fixture(scope="module")
def fused():
    camera = hf.Camera.preset("ros").scaled(2)  # 160x120: 1000 calls in seconds
    data = hf.open_dataset("synthetic:room", camera=camera, frames=3)
    p = hf.Pipeline({"volume": {"voxel_m": 0.04}}, camera)
    frames = list(data)
    results = [p.process(f) for f in frames]
    return p, frames, results


def test_no_leak_frames_and_render(fused):
    p, frames, results = fused
    f = frames[0]
    w, h = f.depth.shape[1], f.depth.shape[0]
    growth, bound = grows(lambda: hf.Frame(f.depth, f.color, f.timestamp).depth.sum(), w * h * 7)
    assert growth < bound, (growth, bound)
    growth, bound = grows(lambda: p.render(results[-1].T_world_camera), w * h * 3)
    assert growth < bound, (growth, bound)


def test_no_leak_mesh_registration_eval(fused):
    p, frames, _ = fused
    mesh = p.extract_mesh()
    mesh_bytes = mesh.vertices.nbytes * 3 + mesh.faces.nbytes
    growth, bound = grows(lambda: p.extract_mesh().vertices, mesh_bytes)
    assert growth < bound, (growth, bound)
    reg = hf.make_registration("icp")
    camera = p.camera
    growth, bound = grows(lambda: reg.align(frames[1], frames[0], camera).information, 200_000)
    assert growth < bound, (growth, bound)
    stamps = np.arange(200) * 0.03
    poses = np.stack([hf.se3_exp([0, 0, 0.01 * i, 0.01 * i, 0, 0]) for i in range(200)])
    growth, bound = grows(lambda: hf.ate((stamps, poses), (stamps, poses))["errors_m"], 200 * 400)
    assert growth < bound, (growth, bound)


def test_no_leak_errors_and_python_objects(fused):
    p = fused[0]
    def bad():
        try:
            # a stamp after every frame fused so far, so the frame's size is what is refused
            p.process(np.zeros((2, 2), np.float32), np.zeros((2, 2, 3), np.uint8), 1e6)
        except hf.Error:
            pass
    tracemalloc.start()
    for _ in range(20):
        bad()
        hf.default_config()
    snapshot = tracemalloc.take_snapshot()
    for _ in range(CALLS):
        bad()
        hf.default_config()
    gc.collect()
    growth = sum(s.size_diff for s in tracemalloc.take_snapshot().compare_to(snapshot, "filename"))
    tracemalloc.stop()
    # one leaked config dict per call would be > 1000 x 10 kB; a leaked traceback per call > 1000 x 500 B
    assert growth < 100_000, growth
