#!/usr/bin/python3
"""Undistorts a TUM RGB-D folder offline with the same remap as core/undistort.h (depth nearest neighbour, colour
bilinear with weights in 1/255, both with the colour camera's model), writing a TUM folder whose camera.txt is the
pinhole part: a cross-check of the in-pipeline undistortion (issue 34), and a way to measure its effect on ATE with
a hashfusion binary that predates it. Needs numpy and python3-open3d (PNG in and out).

  /usr/bin/python3 bench/undistort_tum.py IN_DIR OUT_DIR [fx fy cx cy k1 k2 p1 p2 k3]   (default: TUM fr1)
  /usr/bin/python3 bench/undistort_tum.py --colour-into-ros IN_DIR OUT_DIR

--colour-into-ros: the depth is kept as it is and read with the ROS pinhole (525, 525, 319.5, 239.5); only the colour
is remapped, from the fr1 lens (intrinsics and distortion) into that pinhole: the hypothesis that the Kinect's
on-board registration projected depth through the factory pinhole, so the depth image carries no lens distortion
while the colour image carries the real lens's.
"""
import os
import shutil
import sys

import numpy as np
import open3d as o3d

FR1 = [517.3, 516.5, 318.6, 255.3, 0.2624, -0.9531, -0.0054, 0.0026, 1.1633]


def remap_tables(w, h, fx, fy, cx, cy, k1, k2, p1, p2, k3, out_k=None):
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    ofx, ofy, ocx, ocy = out_k if out_k else (fx, fy, cx, cy)
    x, y = (u - ocx) / ofx, (v - ocy) / ofy
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    su, sv = fx * xd + cx, fy * yd + cy
    inside = (su > -0.5) & (su < w - 0.5) & (sv > -0.5) & (sv < h - 0.5)
    # std::lround: half away from zero (su > -0.5 here, so floor(su + 0.5) matches for su >= 0; clamp the rest).
    nu = np.clip(np.floor(su + 0.5), 0, w - 1).astype(np.int64)
    nv = np.clip(np.floor(sv + 0.5), 0, h - 1).astype(np.int64)
    cu, cv = np.clip(su, 0.0, w - 1.0), np.clip(sv, 0.0, h - 1.0)
    x0 = np.minimum(cu.astype(np.int64), w - 2)
    y0 = np.minimum(cv.astype(np.int64), h - 2)
    wx = np.floor(np.clip(cu - x0, 0.0, 1.0) * 255.0 + 0.5).astype(np.int64)
    wy = np.floor(np.clip(cv - y0, 0.0, 1.0) * 255.0 + 0.5).astype(np.int64)
    return inside, nu, nv, x0, y0, wx, wy


def main():
    args = sys.argv[1:]
    into_ros = "--colour-into-ros" in args
    if into_ros:
        args.remove("--colour-into-ros")
    if len(args) not in (2, 11):
        sys.exit(__doc__)
    src, dst = args[0], args[1]
    model = [float(a) for a in args[2:]] if len(args) == 11 else FR1
    out_k = (525.0, 525.0, 319.5, 239.5) if into_ros else None
    fx, fy, cx, cy = out_k if into_ros else model[:4]
    os.makedirs(os.path.join(dst, "rgb"), exist_ok=True)
    os.makedirs(os.path.join(dst, "depth"), exist_ok=True)
    for f in ("rgb.txt", "depth.txt", "groundtruth.txt"):
        shutil.copy(os.path.join(src, f), dst)
    tables = None
    for listing in ("rgb.txt", "depth.txt"):
        for line in open(os.path.join(src, listing)):
            if line.startswith("#") or not line.strip():
                continue
            name = line.split()[1]
            img = np.asarray(o3d.io.read_image(os.path.join(src, name)))
            h, w = img.shape[:2]
            if tables is None:
                tables = remap_tables(w, h, *model, out_k=out_k)
            inside, nu, nv, x0, y0, wx, wy = tables
            if listing == "depth.txt" and into_ros:
                shutil.copy(os.path.join(src, name), os.path.join(dst, name))
                continue
            if listing == "depth.txt":
                out = np.where(inside, img[nv, nu], 0).astype(img.dtype)
            else:
                im = img.astype(np.int64)
                wxx, wyy = wx[..., None], wy[..., None]
                top = (255 - wxx) * im[y0, x0] + wxx * im[y0, x0 + 1]
                bottom = (255 - wxx) * im[y0 + 1, x0] + wxx * im[y0 + 1, x0 + 1]
                out = ((255 - wyy) * top + wyy * bottom + 255 * 255 // 2) // (255 * 255)
                out = out.astype(np.uint8)  # outside: the border colour repeated (no fixed black edge)
            o3d.io.write_image(os.path.join(dst, name), o3d.geometry.Image(np.ascontiguousarray(out)))
    with open(os.path.join(dst, "camera.txt"), "w") as cam:
        cam.write(f"# {'ROS pinhole, colour remapped from ' if into_ros else 'pinhole part of '}{model}"
                  " (bench/undistort_tum.py)\n"
                  f"fx {fx}\nfy {fy}\ncx {cx}\ncy {cy}\nwidth {tables[1].shape[1]}\nheight {tables[1].shape[0]}\n")


if __name__ == "__main__":
    main()
