#!/usr/bin/env python3
"""Issue 19, depth holes: ATE of `hashfusion run` with the tracking depth's push-pull hole fill off and on.

  python3 bench/fewer_rays_depth_holes.py --out out/depth_holes [--levels 0,1,2,3]
                                          [--inputs rpy0,rpy150,desk,7scenes,holes]

Each level L is a `--config` file {"pyramid": {"fill_holes_levels": L}} (0 = off, the default;
registration/frame_pyramid.h).
The `holes` synthetic preset (the room with 30 % of the depth missing in blobs) is generated once into OUT/holes
(`hashfusion generate --preset holes --frames 90 --seed 1`) and replayed like a real sequence; real inputs come from
../shared/data (skipped when absent). Prints one markdown table (ATE RMSE cm, frames lost, preprocess ms, fps) and
writes it with the raw numbers to OUT/depth_holes.{md,json}. ATE is deterministic per configuration; ms and fps depend
on the machine's load (other work shares the 2 cores).
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# HF_BIN: a copy of the binary, so a rebuild during the runs cannot mix two builds in one table.
HF = os.environ.get("HF_BIN", os.path.join(ROOT, "build/release/apps/hashfusion"))
SHARED = os.path.join(ROOT, "../shared/data")
REAL = {
    "rpy0": "tum_fr1_rpy_first150",
    "rpy150": "tum_fr1_rpy_frames150_269",
    "desk": "tum_fr1_desk_9frames",
    "7scenes": "7scenes_tsdf_fusion_first200",
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--levels", default="0,1,2,3")
    ap.add_argument("--inputs", default="rpy0,rpy150,desk,7scenes,holes")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    inputs = {}
    for name in a.inputs.split(","):
        if name == "holes":
            folder = os.path.join(a.out, "holes")
            if not os.path.isdir(folder):
                subprocess.run([HF, "generate", "--preset", "holes", "--frames", "90", "--seed", "1", "--out", folder],
                               check=True, stdout=subprocess.DEVNULL)
            inputs[name] = folder
        elif os.path.isdir(os.path.join(SHARED, REAL[name])):
            inputs[name] = os.path.join(SHARED, REAL[name])
        else:
            print(f"skipping {name}: {REAL[name]} not in {SHARED}", file=sys.stderr)
    rows = []
    for name, path in inputs.items():
        for level in [int(x) for x in a.levels.split(",")]:
            cfg = os.path.join(a.out, f"fill{level}.json")
            with open(cfg, "w") as f:
                json.dump({"pyramid": {"fill_holes_levels": level}}, f)
            out = os.path.join(a.out, f"{name}_fill{level}")
            subprocess.run([HF, "run", "--input", path, "--config", cfg, "--out", out], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            with open(os.path.join(out, "report.json")) as f:
                r = json.load(f)
            row = {"input": name, "fill_holes_levels": level, "ate_cm": 100 * r["ate_rmse_m"],
                   "lost": r["frames_lost"], "frames": len(r["per_frame"]),
                   "preprocess_ms": r["ms_per_frame"]["preprocess"], "fps": r["fps"]}
            rows.append(row)
            print(row, file=sys.stderr, flush=True)
    lines = ["| input | fill_holes_levels | ATE RMSE (cm) | lost / frames | preprocess (ms) | fps |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['input']} | {r['fill_holes_levels']} | {r['ate_cm']:.2f} | {r['lost']} / {r['frames']} | "
                     f"{r['preprocess_ms']:.1f} | {r['fps']:.1f} |")
    table = "\n".join(lines) + "\n"
    print(table)
    with open(os.path.join(a.out, "depth_holes.md"), "w") as f:
        f.write(table)
    with open(os.path.join(a.out, "depth_holes.json"), "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
