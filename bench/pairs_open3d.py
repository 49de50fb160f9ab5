#!/usr/bin/python3
"""Open3D's hybrid RGB-D odometry (compute_rgbd_odometry, RGBDOdometryJacobianFromHybridTerm) on the pairs of a
bench_pairs JSON: the benchmark peer of issue 34 (python3-open3d from Debian; never part of hashfusion).

  /usr/bin/python3 bench/pairs_open3d.py PAIRS.json OUT.json [--depth-max 6] [--max-k K] [--stride S]

PAIRS.json: a bench_pairs output (--frames-only 1 writes the frame list alone); --max-k / --stride override its
own. OUT.json is rewritten after every k, so a run cut short keeps the k done.

Same frames, same pairs (i, i + k), identity initial guess, the pinhole camera bench_pairs used (raw images: run
bench_pairs with an undistorted camera, e.g. --camera ros, for a like-for-like comparison). Options: Open3D's
defaults (iterations 20/10/5, depth_diff_max 0.03) but depth_max (default 6 m, as issue 34 measured it).
Success = within 3 cm and 2 degrees of the ground-truth relative pose and Open3D's success flag.
"""
import json
import math
import statistics
import sys
import time

import numpy as np
import open3d as o3d


def main():
    args = sys.argv[1:]
    opts = {"--depth-max": 6.0, "--max-k": None, "--stride": None}
    for key in list(opts):
        if key in args:
            j = args.index(key)
            opts[key] = float(args[j + 1])
            del args[j:j + 2]
    depth_max = opts["--depth-max"]
    if len(args) != 2:
        sys.exit("usage: pairs_open3d.py PAIRS.json OUT.json [--depth-max 6] [--max-k K] [--stride S]")
    doc = json.load(open(args[0]))
    max_k = int(opts["--max-k"] or doc["max_k"])
    stride = int(opts["--stride"] or doc["stride"])
    fx, fy, cx, cy, w, h = doc["pinhole"]
    intr = o3d.camera.PinholeCameraIntrinsic(int(w), int(h), fx, fy, cx, cy)
    frames = []
    for f in doc["frame_list"]:
        color = o3d.io.read_image(f["color"])
        depth = o3d.io.read_image(f["depth"])
        scale = 1000.0 if f["depth"].endswith(".depth.png") else 5000.0  # 7-Scenes mm, TUM 1/5000 m
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(color, depth, depth_scale=scale,
                                                                  depth_trunc=depth_max,
                                                                  convert_rgb_to_intensity=True)
        T = np.array(f["T_world_camera_colmajor"]).reshape(4, 4).T
        frames.append((rgbd, T))
    option = o3d.pipelines.odometry.OdometryOption()
    option.depth_max = depth_max
    jac = o3d.pipelines.odometry.RGBDOdometryJacobianFromHybridTerm()
    records = []
    for k in range(1, max_k + 1):
        for i in range(0, len(frames) - k, stride):
            ref, cur = frames[i], frames[i + k]
            t0 = time.perf_counter()
            ok, T, _ = o3d.pipelines.odometry.compute_rgbd_odometry(cur[0], ref[0], intr, np.eye(4), jac, option)
            ms = 1000.0 * (time.perf_counter() - t0)
            gt = np.linalg.inv(ref[1]) @ cur[1]
            err = np.linalg.inv(gt) @ T
            t_err = float(np.linalg.norm(err[:3, 3]))
            r_err = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(err[:3, :3]) - 1.0) / 2.0))))
            records.append({"method": "o3d-hybrid", "mode": "open3d", "variant": "default", "i": i, "k": k,
                            "usable": bool(ok), "t_err_m": t_err, "r_err_deg": r_err,
                            "success": bool(ok) and t_err < 0.03 and r_err < 2.0, "ms": ms})
        n = [r for r in records if r["k"] == k]
        print(f"o3d k={k}: {100.0 * sum(r['success'] for r in n) / max(1, len(n)):.1f} % "
              f"({statistics.mean(r['ms'] for r in n):.0f} ms/pair)", file=sys.stderr, flush=True)
        json.dump({"input": doc["input"], "depth_max_m": depth_max, "open3d": o3d.__version__, "max_k": k,
                   "stride": stride, "records": records}, open(args[1], "w"))


if __name__ == "__main__":
    main()
