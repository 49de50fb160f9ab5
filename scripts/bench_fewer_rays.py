#!/usr/bin/env python3
"""Issue 19, tracking side: `hashfusion run` per sequence and variant, interleaved, into OUT/fewer_rays_tracking.{md,json}.

  python3 scripts/bench_fewer_rays.py --out out/fewer_rays [--rounds 2] [--variants full,importance64,uniform64]
                                      [--inputs rpy0,rpy150,desk,7scenes,room,...] [--synthetic-frames 60]

Each variant is a `--config` file (below: VARIANTS). The runs are interleaved: for every input, every variant runs once
per round, in an order that rotates from round to round, so a change of machine load (other agents share the 2 cores)
falls on all variants alike; each row is the median fps / ms over the rounds (ATE is deterministic per variant, the
script checks that every round gave the same). The 1-minute load average is read before every run and reported.
Runs the Release `hashfusion` (build it first); real inputs come from ../shared/data (skipped when absent).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HF = os.path.join(ROOT, "build/release/apps/hashfusion")
SHARED = os.path.join(ROOT, "../shared/data")

REAL = {
    "rpy0": "tum_fr1_rpy_first150",
    "rpy150": "tum_fr1_rpy_frames150_269",
    "desk": "tum_fr1_desk_9frames",
    "7scenes": "7scenes_tsdf_fusion_first200",
}
SYNTHETIC = ["room", "wall", "corridor", "textureless", "fast", "holes", "exposure"]


def selection(mode, budget, extra=None):
    """Rows from `budget` of every 16 x 16 tile of the finest tracking level, photometric rows at every selected pixel
    (the selection replaces the photometric step-2 grid, which is itself a uniform subsampling)."""
    ro = {"row_selection": mode, "row_selection_budget": budget, "finest_level_photometric_step": 1}
    ro.update(extra or {})
    return {"registration_options": ro}


def variants():
    v = {"full": {}}
    for b in (16, 32, 64, 128):
        v[f"importance{b}"] = selection(1, b)
        v[f"uniform{b}"] = selection(2, b)
        v[f"importance{b}_sampled"] = dict(selection(1, b), tracking_raycast="sampled")
        v[f"uniform{b}_sampled"] = dict(selection(2, b), tracking_raycast="sampled")
    v["full_sampled"] = {"tracking_raycast": "sampled"}
    return v


def loadavg():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def run_one(inp, variant, config, out, synthetic_frames, tmp):
    cfg = os.path.join(tmp, variant + ".json")
    with open(cfg, "w") as f:
        json.dump(config, f)
    run_dir = os.path.join(tmp, "runs", f"{inp}__{variant}")
    if inp in REAL:
        args = ["--input", os.path.join(SHARED, REAL[inp])]
    else:
        args = ["--input", "synthetic:" + inp, "--synthetic-frames", str(synthetic_frames)]
    load = loadavg()
    p = subprocess.run([HF, "run", *args, "--out", run_dir, "--config", cfg], capture_output=True, text=True)
    if p.returncode != 0:
        print(f"bench_fewer_rays: {inp} {variant} failed: {p.stderr.strip()[-300:]}", file=sys.stderr)
        return None
    r = json.load(open(os.path.join(run_dir, "report.json")))
    frames = r["per_frame"]
    rows = [f["inliers"] for f in frames if "inliers" in f]
    ms = r["ms_per_frame"]
    return {
        "ate_m": r["ate_rmse_m"], "fps": r["fps"], "lost": r["frames_lost"], "frames": r["frames"],
        "ms_total": ms["total"], "ms_preprocess": ms["preprocess"], "ms_track": ms["track"],
        "ms_integrate": ms["integrate"], "ms_raycast": ms["raycast"],
        "rows_mean": statistics.mean(rows) if rows else None, "load1": load,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--variants", default="full,importance64,uniform64")
    ap.add_argument("--inputs", default=",".join(list(REAL) + SYNTHETIC))
    ap.add_argument("--synthetic-frames", type=int, default=60)
    a = ap.parse_args()
    if not os.access(HF, os.X_OK):
        sys.exit(f"bench_fewer_rays: build first ({HF} missing)")
    all_variants = variants()
    names = a.variants.split(",")
    for n in names:
        if n not in all_variants:
            sys.exit(f"bench_fewer_rays: unknown variant '{n}' (known: {', '.join(all_variants)})")
    inputs = [i for i in a.inputs.split(",") if i not in REAL or os.path.isdir(os.path.join(SHARED, REAL[i]))]
    os.makedirs(a.out, exist_ok=True)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for inp in inputs:
            for rnd in range(a.rounds):
                order = names[rnd % len(names):] + names[:rnd % len(names)]
                for v in order:
                    print(f"bench_fewer_rays: {inp} {v} round {rnd + 1}", file=sys.stderr)
                    r = run_one(inp, v, all_variants[v], a.out, a.synthetic_frames, tmp)
                    if r is not None:
                        results.setdefault((inp, v), []).append(r)
    rows = []
    for (inp, v), rs in results.items():
        med = lambda k: statistics.median(x[k] for x in rs)
        ates = {x["ate_m"] for x in rs}
        rows.append({
            "input": inp, "variant": v, "config": all_variants[v], "rounds": len(rs),
            "ate_m": rs[0]["ate_m"], "ate_same_every_round": len(ates) == 1, "lost": rs[0]["lost"],
            "frames": rs[0]["frames"], "fps": med("fps"), "ms_total": med("ms_total"),
            "ms_preprocess": med("ms_preprocess"), "ms_track": med("ms_track"), "ms_integrate": med("ms_integrate"),
            "ms_raycast": med("ms_raycast"), "rows_mean": rs[0]["rows_mean"],
            "load1": [x["load1"] for x in rs],
        })
    doc = {"command": " ".join(sys.argv), "commit": subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                                                  capture_output=True, text=True).stdout.strip(),
           "nproc": os.cpu_count(), "rows": rows}
    tmp_json = os.path.join(a.out, ".fewer_rays_tracking.json.tmp")
    with open(tmp_json, "w") as f:
        json.dump(doc, f, indent=1)
    os.replace(tmp_json, os.path.join(a.out, "fewer_rays_tracking.json"))
    md = ["| input | variant | ATE cm | lost | rows/frame | fps | ms total | track | raycast | load1 |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ate = "-" if r["ate_m"] is None else f"{100 * r['ate_m']:.2f}" + ("" if r["ate_same_every_round"] else "*")
        rm = "-" if r["rows_mean"] is None else f"{r['rows_mean']:.0f}"
        md.append(f"| {r['input']} | {r['variant']} | {ate} | {r['lost']}/{r['frames']} | {rm} | {r['fps']:.1f} | "
                  f"{r['ms_total']:.1f} | {r['ms_track']:.1f} | {r['ms_raycast']:.1f} | "
                  f"{'/'.join(f'{x:.1f}' for x in r['load1'])} |")
    tmp_md = os.path.join(a.out, ".fewer_rays_tracking.md.tmp")
    with open(tmp_md, "w") as f:
        f.write("\n".join(md) + "\n")
    os.replace(tmp_md, os.path.join(a.out, "fewer_rays_tracking.md"))
    print("\n".join(md))


if __name__ == "__main__":
    main()
