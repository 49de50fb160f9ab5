#!/usr/bin/env python3
"""A TUM folder re-timed to each frame's middle row: a rolling-shutter hypothesis tested with the reference (issue 34).

    PYTHONPATH=build/release/python /usr/bin/python3 bench/rolling_shutter_tum.py IN_DIR OUT_DIR TAU_S [both|colour|depth]

A rolling shutter exposes row v at t + TAU (v - cy) / H (TAU: the signed top-to-bottom readout time). A camera turning
at omega (rad/s, in the camera's frame) then sees the point p of row v rotated by exp(-[omega dt]) against the
middle row's instant; the remap undoes that per pixel: target ray r' of pixel (u', v'), source ray r = exp(-[omega
dt]) r' (dt from the source row, one refinement from the target row's), depth nearest-neighbour with its z rotated
(first order in omega dt, which is below 0.03 rad here), colour bilinear. omega is the REFERENCE's (an oracle: the
rotation between the frames before and after over their time), so a gain here is an upper bound of what the motion
prior could earn in the pipeline. Rotation only: over a readout the translation of a hand-held camera is < 1 mm.
TAU 0 writes the frames as read (the control: `hashfusion run` on it gives the original folder's trajectory). Every
frame is written at its colour stamp for both images; groundtruth.txt is copied. The folder name should keep
"fr1" so `hashfusion run` reads it with the same camera.
"""
import os
import shutil
import struct
import sys
import zlib

import numpy as np

import hashfusion as hf


def png_write(path, arr):
    """8-bit RGB or 16-bit grey PNG, no filter (numpy only)."""
    h, w = arr.shape[:2]
    if arr.dtype == np.uint16:
        raw = b"".join(b"\x00" + arr[y].astype(">u2").tobytes() for y in range(h))
        colour_type, depth = 0, 16
    else:
        raw = b"".join(b"\x00" + arr[y].tobytes() for y in range(h))
        colour_type, depth = 2, 8

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, colour_type, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 1)) + chunk(b"IEND", b""))


def log_so3(R):
    theta = np.arccos(max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0)))
    if theta < 1e-9:
        return np.zeros(3)
    return theta / (2.0 * np.sin(theta)) * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    src, out, tau = sys.argv[1], sys.argv[2], float(sys.argv[3])
    mode = sys.argv[4] if len(sys.argv) > 4 else "both"
    if mode not in ("both", "colour", "depth"):
        sys.exit("rolling_shutter_tum: mode is both, colour or depth")
    d = hf.open_dataset(src)
    cam = d.camera
    fx, fy, cx, cy, W, H = cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height
    os.makedirs(os.path.join(out, "rgb"), exist_ok=True)
    os.makedirs(os.path.join(out, "depth"), exist_ok=True)
    frames = [d[i] for i in range(len(d))]
    uu, vv = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    rays = np.stack([(uu - cx) / fx, (vv - cy) / fy, np.ones_like(uu)], -1)
    rgb_list, depth_list = [], []
    for i, f in enumerate(frames):
        a, b = frames[max(i - 1, 0)], frames[min(i + 1, len(frames) - 1)]
        omega = log_so3(a.T_world_camera_gt[:3, :3].T @ b.T_world_camera_gt[:3, :3]) / max(b.timestamp - a.timestamp,
                                                                                           1e-6)
        src_rays = rays - np.cross(omega[None, None, :] * (tau * (vv - cy) / H)[..., None], rays)
        v_src = fy * src_rays[..., 1] / src_rays[..., 2] + cy
        wdt = omega[None, None, :] * (tau * (v_src - cy) / H)[..., None]  # the source row's time
        src_rays = rays - np.cross(wdt, rays)
        us = fx * src_rays[..., 0] / src_rays[..., 2] + cx
        vs = fy * src_rays[..., 1] / src_rays[..., 2] + cy
        ui, vi = np.rint(us).astype(int), np.rint(vs).astype(int)
        inside = (ui >= 0) & (ui < W) & (vi >= 0) & (vi < H)
        depth = np.asarray(f.depth, dtype=float)
        colour = np.asarray(f.color).astype(float)
        z_src = np.where(inside, depth[np.clip(vi, 0, H - 1), np.clip(ui, 0, W - 1)], 0.0)
        p = z_src[..., None] * src_rays / src_rays[..., 2:3]
        z_new = np.where(z_src > 0, p[..., 2] + np.cross(wdt, p)[..., 2], 0.0)
        x0 = np.clip(np.floor(us).astype(int), 0, W - 2)
        y0 = np.clip(np.floor(vs).astype(int), 0, H - 2)
        ax = np.clip(us - x0, 0, 1)[..., None]
        ay = np.clip(vs - y0, 0, 1)[..., None]
        col = ((1 - ay) * ((1 - ax) * colour[y0, x0] + ax * colour[y0, x0 + 1]) +
               ay * ((1 - ax) * colour[y0 + 1, x0] + ax * colour[y0 + 1, x0 + 1]))
        col = np.where(inside[..., None], col, colour)
        if mode == "colour":
            z_new = depth
        if mode == "depth":
            col = colour
        stamp = "%.6f" % f.timestamp
        png_write(os.path.join(out, "rgb", stamp + ".png"), np.clip(col + 0.5, 0, 255).astype(np.uint8))
        png_write(os.path.join(out, "depth", stamp + ".png"), np.clip(z_new * 5000 + 0.5, 0, 65535).astype(np.uint16))
        rgb_list.append("%s rgb/%s.png" % (stamp, stamp))
        depth_list.append("%s depth/%s.png" % (stamp, stamp))
    with open(os.path.join(out, "rgb.txt"), "w") as f:
        f.write("\n".join(rgb_list) + "\n")
    with open(os.path.join(out, "depth.txt"), "w") as f:
        f.write("\n".join(depth_list) + "\n")
    shutil.copy(os.path.join(src, "groundtruth.txt"), os.path.join(out, "groundtruth.txt"))
    print("rolling_shutter_tum: %d frames re-timed with TAU %g s (%s) in %s" % (len(frames), tau, mode, out))


if __name__ == "__main__":
    main()
