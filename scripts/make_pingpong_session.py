#!/usr/bin/env python3
"""A long pseudo-session from a short TUM excerpt (issue 33): its frames played forward, backward, forward, ...

    python3 scripts/make_pingpong_session.py OUT_DIR TUM_DIR [TUM_DIR ...] [--passes 3] [--rate-hz 30]

The excerpts (contiguous, in order) are joined; the session plays them forward, then backward, then forward again
(--passes legs), re-stamped at --rate-hz so time always increases. OUT_DIR gets rgb/ and depth/ of symbolic links
(one per played frame, named by its new stamp), rgb.txt, depth.txt and groundtruth.txt: each frame keeps its
own ground-truth pose (the recording's, linearly interpolated at the frame's original colour stamp; rotation by
normalised quaternion interpolation), written at the new stamp. Turning round at the ends revisits the whole
excerpt, so the session closes loops where the excerpt alone does not.
"""
import argparse
import bisect
import math
import os
import sys


def read_list(path):
    rows = []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        parts = line.split()
        rows.append((float(parts[0]), parts[1:]))
    return rows


def nearest(stamps, t):
    i = bisect.bisect_left(stamps, t)
    best = min((j for j in (i - 1, i) if 0 <= j < len(stamps)), key=lambda j: abs(stamps[j] - t))
    return best


def interpolate_pose(gt, t):
    stamps = [s for s, _ in gt]
    i = bisect.bisect_left(stamps, t)
    if i == 0 or i >= len(gt):
        return [float(v) for v in gt[min(max(i, 0), len(gt) - 1)][1]]
    (t0, a), (t1, b) = gt[i - 1], gt[i]
    a = [float(v) for v in a]
    b = [float(v) for v in b]
    w = (t - t0) / (t1 - t0) if t1 > t0 else 0.0
    p = [a[k] + w * (b[k] - a[k]) for k in range(3)]
    qa, qb = a[3:], b[3:]
    if sum(x * y for x, y in zip(qa, qb)) < 0:
        qb = [-x for x in qb]
    q = [qa[k] + w * (qb[k] - qa[k]) for k in range(4)]
    n = math.sqrt(sum(x * x for x in q))
    return p + [x / n for x in q]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("--passes", type=int, default=3)
    ap.add_argument("--rate-hz", type=float, default=30.0)
    args = ap.parse_args()
    frames = []  # (rgb path, depth path, original stamp)
    gt = []
    for d in args.inputs:
        d = os.path.realpath(d)
        rgb = read_list(os.path.join(d, "rgb.txt"))
        depth = read_list(os.path.join(d, "depth.txt"))
        depth_stamps = [s for s, _ in depth]
        for s, (name,) in rgb:
            j = nearest(depth_stamps, s)
            if abs(depth_stamps[j] - s) > 0.02:
                continue  # no depth for this colour frame (the reader would skip it too)
            frames.append((os.path.join(d, name), os.path.join(d, depth[j][1][0]), s))
        for s, v in read_list(os.path.join(d, "groundtruth.txt")):
            gt.append((s, v))
    gt.sort()
    dedup = []
    for s, v in gt:
        if not dedup or s != dedup[-1][0]:
            dedup.append((s, v))
    gt = dedup
    order = []
    for leg in range(args.passes):
        order += frames if leg % 2 == 0 else frames[::-1]  # the turning frame is held for two frames
    os.makedirs(os.path.join(args.out, "rgb"), exist_ok=True)
    os.makedirs(os.path.join(args.out, "depth"), exist_ok=True)
    t0 = 1000000.0
    with open(os.path.join(args.out, "rgb.txt"), "w") as rgb_txt, \
         open(os.path.join(args.out, "depth.txt"), "w") as depth_txt, \
         open(os.path.join(args.out, "groundtruth.txt"), "w") as gt_txt:
        # The "file:" line names the recording as TUM's lists do: the camera preset follows it (io/dataset.h).
        rgb_txt.write("# color images\n# file: 'rgbd_dataset_freiburg1_pingpong.bag' (pseudo-session of %s, %d legs)\n"
                      "# timestamp filename\n" % (" + ".join(args.inputs), args.passes))
        depth_txt.write("# depth maps\n# pseudo-session\n# timestamp filename\n")
        gt_txt.write("# ground truth trajectory\n# pseudo-session\n# timestamp tx ty tz qx qy qz qw\n")
        for i, (rgb, depth, s) in enumerate(order):
            t = t0 + i / args.rate_hz
            name = "%.6f.png" % t
            for sub, src in (("rgb", rgb), ("depth", depth)):
                dst = os.path.join(args.out, sub, name)
                if os.path.lexists(dst):
                    os.remove(dst)
                os.symlink(src, dst)
            rgb_txt.write("%.6f rgb/%s\n" % (t, name))
            depth_txt.write("%.6f depth/%s\n" % (t, name))
            gt_txt.write("%.6f %s\n" % (t, " ".join("%.6f" % v for v in interpolate_pose(gt, s))))
    print("%d frames (%d per leg) in %s" % (len(order), len(frames), args.out), file=sys.stderr)


if __name__ == "__main__":
    main()
