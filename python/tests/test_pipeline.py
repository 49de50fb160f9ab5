"""The pipeline, registration and evaluation from Python against the CLI: same trajectory, same metrics."""
import json

import numpy as np
import pytest

import hashfusion as hf
from conftest import run_cli

FRAMES = 12


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory, cli, camera):
    """`hashfusion run` on the synthetic room at the test camera: its folder and report.json."""
    work = tmp_path_factory.mktemp("cli")
    camera.save(str(work / "camera.json"))
    out = work / "run"
    r = run_cli(cli, "run", "--input", "synthetic:room", "--synthetic-frames", str(FRAMES), "--camera",
                str(work / "camera.json"), "--out", str(out))
    assert r.returncode == 0, r.stderr
    return out, json.loads((out / "report.json").read_text())


def test_run_equals_cli(cli_run, synthetic):
    out, report = cli_run
    cli_stamps, cli_poses = hf.read_trajectory(str(out / "trajectory.txt"))
    data = synthetic(frames=FRAMES)
    p = hf.Pipeline(report["config"], data.camera)
    result = p.run(data)
    stamps, poses = result.trajectory
    assert len(stamps) == FRAMES and not result.interrupted
    # trajectory.txt holds 17 significant digits: the same computation agrees to rounding
    np.testing.assert_allclose(stamps, cli_stamps, rtol=0, atol=1e-9)
    np.testing.assert_allclose(poses, cli_poses, rtol=0, atol=1e-9)
    assert result.report["ate_rmse_m"] == pytest.approx(report["ate_rmse_m"], abs=1e-9)
    assert result.report["config"] == report["config"]


def test_process_loop_equals_run(cli_run, synthetic):
    _, report = cli_run
    data = synthetic(frames=FRAMES)
    p = hf.Pipeline(report["config"], data.camera)
    online = [p.process(f).T_world_camera for f in data]
    p.finish()
    again = hf.Pipeline(report["config"], data.camera).run(synthetic(frames=FRAMES))
    np.testing.assert_allclose(np.stack(online), again.online_trajectory[1], rtol=0, atol=1e-12)
    stamps, poses = p.corrected_trajectory()  # (stamps, poses), as hf.ate takes it
    np.testing.assert_array_equal(stamps, again.trajectory[0])
    np.testing.assert_allclose(poses, again.trajectory[1], rtol=0, atol=1e-12)
    # process(depth, color, timestamp) with the arrays of the frames is the same call
    q = hf.Pipeline(report["config"], data.camera)
    arrays = [q.process(f.depth, f.color, f.timestamp, f.T_world_camera_gt).T_world_camera
              for f in synthetic(frames=3)]
    np.testing.assert_allclose(np.stack(arrays), np.stack(online[:3]), rtol=0, atol=1e-12)


def test_mesh_and_render(synthetic):
    data = synthetic(frames=4)
    p = hf.Pipeline({"volume": {"voxel_m": 0.02}}, data.camera)
    results = [p.process(f) for f in data]
    mesh = p.extract_mesh()
    v, faces = mesh.vertices, mesh.faces
    assert len(faces) > 1000 and v.dtype == np.float32 and faces.dtype == np.int32
    assert faces.min() >= 0 and faces.max() < len(v)
    assert mesh.colors.shape == v.shape and mesh.normals.shape == v.shape
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-3)
    # the room's surfaces lie in front of the first camera: every vertex within the sensor's range of it
    T_camera_world = np.linalg.inv(results[0].T_world_camera)
    z = (v.astype(np.float64) @ T_camera_world[:3, :3].T + T_camera_world[:3, 3])[:, 2]
    assert np.median(z) > 0.3
    image = p.render(results[-1].T_world_camera)
    assert image.shape == (data.camera.height, data.camera.width, 3) and image.dtype == np.uint8
    assert image.reshape(-1, 3).max(axis=1).mean() > 20  # shaded surface, not an empty background


def test_registration_recovers_relative_motion(synthetic, camera):
    frames = list(synthetic(frames=3))
    ref, cur = frames[0], frames[2]
    truth = np.linalg.inv(ref.T_world_camera_gt) @ cur.T_world_camera_gt  # T_ref_cur
    moved_m = np.linalg.norm(truth[:3, 3])
    assert moved_m > 0.005  # the room's trajectory moves between these frames
    assert "combined" in hf.registration_names()
    for name in ("icp", "combined"):
        reg = hf.make_registration(name)
        assert reg.name == name
        res = reg.align(cur, ref, camera)
        assert res.status in ("good", "poor"), res.message
        err = np.linalg.inv(truth) @ res.T_ref_cur
        # the noisy synthetic frames register to well under the motion between them (1 mm at the test size)
        assert np.linalg.norm(err[:3, 3]) < 0.2 * moved_m
        assert np.degrees(np.linalg.norm(hf.se3_log(err)[:3])) < 0.5
    with pytest.raises(hf.Error, match="unknown registration"):
        hf.make_registration("no-such-method")


def test_eval_equals_cli(cli_run, cli, tmp_path):
    out, _ = cli_run
    gt_path = str(tmp_path / "gt.txt")
    gt = hf.open_dataset("synthetic:room", frames=FRAMES).ground_truth
    hf.write_trajectory(gt_path, gt)
    est_path = str(out / "trajectory.txt")
    r = run_cli(cli, "eval", "--gt", gt_path, "--est", est_path, "--json")
    assert r.returncode == 0, r.stderr
    cli_metrics = json.loads(r.stdout)
    metrics = hf.evaluate(gt_path, est_path)
    for key, value in metrics.items():
        assert cli_metrics[key] == value, key
    ate = hf.ate(gt, hf.read_trajectory(est_path))
    assert ate["ate_rmse_m"] == cli_metrics["ate_rmse_m"] and ate["pairs"] == cli_metrics["pairs"]
    assert np.sqrt(np.mean(ate["errors_m"] ** 2)) == pytest.approx(ate["ate_rmse_m"], rel=1e-12)
    # RPE over 0.1 s, so that the short sequence has pairs
    rpe = hf.rpe(gt_path, est_path, delta_s=0.1)
    r = run_cli(cli, "eval", "--gt", gt_path, "--est", est_path, "--json", "--delta", "0.1")
    cli_rpe = json.loads(r.stdout)
    assert rpe["rpe_pairs"] > 0 and rpe["rpe_trans_rmse_m_per_s"] == cli_rpe["rpe_trans_rmse_m_per_s"]
    assert rpe["rpe_rot_max_deg_per_s"] == cli_rpe["rpe_rot_max_deg_per_s"]
