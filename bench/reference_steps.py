#!/usr/bin/env python3
"""Where a dataset's reference trajectory disagrees with two independent depth-only registrations (issue 34).

    PYTHONPATH=build/release/python /usr/bin/python3 bench/reference_steps.py DATASET [--frames N] [--jump-mm 12]
        [--agree-mm 5] [--trajectory TRAJ --replace]

Every consecutive pair (i, i+1) of DATASET (any folder `hashfusion run` reads that has a reference) is registered by
`icp` and by `sdf` from the identity, each method's defaults (`hf.make_registration(m).align(d[i+1], d[i],
d.camera)`): one aligns the frame's points to the other frame's, the other to that frame's TSDF. Printed: the median
distance between each method's step and the reference's step (the translation of their difference, mm), the median
between the two methods, and every pair where both methods agree with each other within --agree-mm but disagree with
the reference by more than --jump-mm: a step of the reference that two trackers independently contradict.

With --trajectory TRAJ (a `hashfusion run` trajectory.txt of the same frames) and --replace, each flagged step of the
reference is replaced by TRAJ's own step there (the reference's poses after it moved rigidly by the difference) and
the ATE (hf.ate: slam/eval's, Horn alignment, no scale) of TRAJ is printed against the reference as given and as
mended: how much of TRAJ's error is that step of the reference.
"""
import argparse
import sys

import numpy as np

import hashfusion as hf


def step_error_mm(T_ref_step, T_est_step):
    return 1000.0 * np.linalg.norm((np.linalg.inv(T_ref_step) @ T_est_step)[:3, 3])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("--frames", type=int, default=0, help="the first N frames (0 = all)")
    ap.add_argument("--jump-mm", type=float, default=12.0)
    ap.add_argument("--agree-mm", type=float, default=5.0)
    ap.add_argument("--trajectory")
    ap.add_argument("--replace", action="store_true")
    a = ap.parse_args()

    d = hf.open_dataset(a.dataset)
    n = len(d) if a.frames <= 0 else min(a.frames, len(d))
    regs = {m: hf.make_registration(m) for m in ("icp", "sdf")}
    gt = []
    rows = []  # (i, reference step mm, icp error, sdf error, icp vs sdf)
    prev = d[0]
    gt.append(prev.T_world_camera_gt)
    for i in range(1, n):
        cur = d[i]
        gt.append(cur.T_world_camera_gt)
        G = np.linalg.inv(prev.T_world_camera_gt) @ cur.T_world_camera_gt
        T = {m: np.array(r.align(cur, prev, d.camera).T_ref_cur) for m, r in regs.items()}
        rows.append((i - 1, 1000.0 * np.linalg.norm(G[:3, 3]), step_error_mm(G, T["icp"]),
                     step_error_mm(G, T["sdf"]), step_error_mm(T["icp"], T["sdf"])))
        prev = cur
        print("\rpairs %d/%d" % (i, n - 1), end="", file=sys.stderr)
    print(file=sys.stderr)
    A = np.array(rows)
    print("%s: %d pairs; median step error against the reference: icp %.1f mm, sdf %.1f mm; icp against sdf %.1f mm"
          % (a.dataset, len(A), np.median(A[:, 2]), np.median(A[:, 3]), np.median(A[:, 4])))
    flagged = [int(r[0]) for r in A if min(r[2], r[3]) > a.jump_mm and r[4] < a.agree_mm]
    for r in A:
        if int(r[0]) in flagged:
            print("reference step %d -> %d: %.1f mm; icp %.1f mm and sdf %.1f mm off it, %.1f mm from each other"
                  % (r[0], r[0] + 1, r[1], r[2], r[3], r[4]))
    if not flagged:
        print("no step of the reference is contradicted by both methods")
    if a.trajectory and a.replace:
        stamps, E = hf.read_trajectory(a.trajectory)
        if len(E) != n:
            sys.exit("reference_steps: %s has %d poses, the dataset %d frames" % (a.trajectory, len(E), n))
        G = np.array([np.array(T) for T in gt])
        mended = G.copy()
        for j in flagged:  # the reference after step j moved so that its step j is the trajectory's
            C = mended[j] @ np.linalg.inv(E[j]) @ E[j + 1] @ np.linalg.inv(mended[j + 1])
            mended[j + 1:] = C @ mended[j + 1:]
        # slam/eval's ATE (hf.ate: Horn alignment, no scale), the reference at the trajectory's own stamps.
        before = hf.ate((stamps, G), (stamps, E))["ate_rmse_m"]
        after = hf.ate((stamps, mended), (stamps, E))["ate_rmse_m"]
        print("ATE of %s: %.3f cm against the reference, %.3f cm with the flagged steps replaced"
              % (a.trajectory, 100 * before, 100 * after))

if __name__ == "__main__":
    main()
