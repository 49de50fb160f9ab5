#!/usr/bin/env bash
# scripts/bench_sdf_tracking.sh OUT_DIR: `sdf` (volume tracking, no tracking raycast) against `combined` (the
# default) and `icp` on every real sequence in ../shared/data, through `hashfusion run` with the defaults otherwise.
# The three methods run interleaved per input, so machine load affects them alike. Writes OUT_DIR/sdf_tracking.md.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/bench_lib.sh
bench_init bench_sdf_tracking "${1:-out/bench_sdf_tracking}"
for input in tum_fr1_rpy_first150 tum_fr1_rpy_frames150_269 tum_fr1_desk_9frames 7scenes_tsdf_fusion_first200; do
  for method in sdf combined icp; do
    bench_run "${input}__$method" "$shared/$input" --registration "$method"
  done
done
python3 - "$out" "$(uptime)" <<'PY'
import json, os, sys
sys.path.insert(0, "scripts")
from bench_runs import runs  # noqa: E402
out, load = sys.argv[1], sys.argv[2]
rows = ["| input | method | frames | lost | fallback | ATE cm | RPE cm/s | fps | track ms | raycast ms | total ms |",
        "|---|---|---|---|---|---|---|---|---|---|---|"]
for name, method, r in runs(out):
    ms = r["ms_per_frame"]
    cm = lambda v: "-" if v is None else f"{v * 100:.2f}"
    rows.append(f"| {name} | {method} | {r['frames']} | {r['frames_lost']} | {r['frames_fallback']} | "
                f"{cm(r.get('ate_rmse_m'))} | {cm(r.get('rpe_trans_m_per_s'))} | {r['fps']:.1f} | {ms['track']:.1f} | "
                f"{ms['raycast']:.1f} | {ms['total']:.1f} |")
open(os.path.join(out, "sdf_tracking.md"), "w").write("\n".join(rows) + f"\n\nLoad at the end: {load}\n")
print("\n".join(rows))
PY
