#!/usr/bin/env python3
"""Tables of the large-motion pairs (issue 34): bench_pairs JSON files and bench/pairs_open3d.py's, merged.

  python3 bench/pairs_report.py OUT.md PAIRS.json [OPEN3D.json ...]

One table per input sequence; per (method, mode, variant): the success rate (within 3 cm and 2 degrees of the
ground-truth relative pose, status usable) at every k, the median translation / rotation error of the successful
pairs at k = 1, the pairs, and ms per pair. Also writes OUT.json with the same numbers.
"""
import json
import os
import statistics
import sys


def main():
    out_md, inputs = sys.argv[1], sys.argv[2:]
    records, sources = [], []
    for path in inputs:
        doc = json.load(open(path))
        seq = os.path.basename(os.path.normpath(doc["input"]))
        records += [dict(r, input=seq) for r in doc["records"]]
        sources.append(f"{os.path.basename(path)}: input {doc['input']}"
                       + (f", camera {doc['camera']}" if "camera" in doc else "")
                       + (f", stride {doc['stride']}" if "stride" in doc else "")
                       + (f", Open3D {doc['open3d']} depth_max {doc['depth_max_m']} m" if "open3d" in doc else ""))
    groups = {}
    for r in records:
        groups.setdefault((r["input"], r["method"], r["mode"], r["variant"]), []).append(r)
    ks = sorted({r["k"] for r in records})
    rows = []
    for key, rs in groups.items():
        row = {"input": key[0], "method": key[1], "mode": key[2], "variant": key[3], "pairs": len(rs),
               "success": {}}
        for k in ks:
            n = [r for r in rs if r["k"] == k]
            row["success"][k] = 100.0 * sum(r["success"] for r in n) / len(n) if n else None
        ok1 = [r for r in rs if r["k"] == 1 and r["success"]]
        row["k1_median_t_mm"] = 1000.0 * statistics.median(r["t_err_m"] for r in ok1) if ok1 else None
        row["k1_median_r_deg"] = statistics.median(r["r_err_deg"] for r in ok1) if ok1 else None
        row["ms_per_pair"] = statistics.mean(r["ms"] for r in rs)
        rows.append(row)
    rows.sort(key=lambda r: (r["input"], r["method"], r["mode"], r["variant"]))
    f = lambda v, p=1: "-" if v is None else f"{v:.{p}f}"
    with open(out_md, "w") as md:
        md.write("Sources: " + "; ".join(sources) + "\n")
        for seq in sorted({r["input"] for r in rows}):
            md.write(f"\n{seq}\n\n| method | mode | variant | " + " | ".join(f"k={k}" for k in ks) +
                     " | k=1 median mm / deg | pairs | ms per pair |\n|" + "---|" * (len(ks) + 6) + "\n")
            for r in rows:
                if r["input"] != seq:
                    continue
                md.write(f"| {r['method']} | {r['mode']} | {r['variant']} | " +
                         " | ".join(f(r["success"][k]) for k in ks) +
                         f" | {f(r['k1_median_t_mm'], 2)} / {f(r['k1_median_r_deg'], 3)} | {r['pairs']} |"
                         f" {f(r['ms_per_pair'], 0)} |\n")
    json.dump(rows, open(out_md[:-3] + ".json" if out_md.endswith(".md") else out_md + ".json", "w"), indent=1)
    print(open(out_md).read())


if __name__ == "__main__":
    main()
