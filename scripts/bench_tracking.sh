#!/usr/bin/env bash
# scripts/bench_tracking.sh OUT_DIR: tracking that recovers (issue 13) on every real sequence in ../shared/data and
# on the synthetic loop / kidnap presets, with loop closure off, on (the default) and on + --global. Runs the
# Release `hashfusion run` (build it first: scripts/build.sh release) and writes OUT_DIR/tracking.{md,json}.
# fr1/rpy frames 0-269 are the two shared excerpts joined into one folder of links (they are contiguous).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/bench_lib.sh
bench_init bench_tracking "${1:-out/bench_tracking}"

bench_fr1_rpy_0_269  # $work/tum_fr1_rpy_frames0_269
joined="$work/tum_fr1_rpy_frames0_269"
echo '{"loop_closure": {"enabled": false}}' > "$work/off.json"

inputs=(
  "$shared/tum_fr1_rpy_first150"
  "$shared/tum_fr1_rpy_frames150_269"
  "$joined"
  "$shared/tum_fr1_desk_9frames"
  "$shared/7scenes_tsdf_fusion_first200"
  "synthetic:loop"
  "synthetic:kidnap"
)
for input in "${inputs[@]}"; do
  name="$(bench_input_name "$input")"
  frames=()
  [[ "$name" == synthetic_loop ]] && frames=(--synthetic-frames 250)
  [[ "$name" == synthetic_kidnap ]] && frames=(--synthetic-frames 95)
  bench_run "${name}__off" "$input" "${frames[@]}" --config "$work/off.json"
  bench_run "${name}__on" "$input" "${frames[@]}"
  bench_run "${name}__global" "$input" "${frames[@]}" --global
done

python3 - "$out" <<'EOF'
import json, os, sys
sys.path.insert(0, "scripts")
from bench_runs import runs  # noqa: E402
out = sys.argv[1]
rows = []
for name, mode, r in runs(out):
    ms = r["ms_per_frame"]
    rows.append({
        "input": name, "mode": mode, "frames": r["frames"], "lost": r["frames_lost"],
        "lost_pct": 100.0 * r["frames_lost"] / max(r["frames"], 1), "coverage": r["coverage"],
        "lost_spells": r["lost_spells"], "longest_lost_spell": r["longest_lost_spell"],
        "odometry": r["frames_odometry"], "relocalised": r["frames_relocalised"], "fallback": r["frames_fallback"],
        "keyframes": r["keyframes"], "loops": r["loops_closed"], "reintegrated": r["frames_reintegrated"],
        "ate_m": r["ate_rmse_m"], "ate_online_m": r["ate_online_m"], "fps": r["fps"],
        "ms_per_frame": ms["total"], "worst_frame_ms": r["worst_frame_ms"], "loop_worst_ms": r["loop_worst_ms"],
        "finish_ms": r["finish_ms"],
    })
tmp = os.path.join(out, ".tracking.json.tmp")
with open(tmp, "w") as f:
    json.dump(rows, f, indent=2)
os.replace(tmp, os.path.join(out, "tracking.json"))
def cm(v):
    return "-" if v is None else "%.2f" % (100.0 * v)
lines = ["| input | loop closure | frames | lost (%) | spells (longest) | odometry | relocalised | fallback | keyframes | loops | re-fused | ATE final cm | ATE online cm | fps | worst frame ms | worst loop ms | finish ms |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    lines.append("| %s | %s | %d | %d (%.1f) | %d (%d) | %d | %d | %d | %d | %d | %d | %s | %s | %.1f | %.0f | %.0f | %.0f |" % (
        r["input"], r["mode"], r["frames"], r["lost"], r["lost_pct"], r["lost_spells"], r["longest_lost_spell"],
        r["odometry"], r["relocalised"], r["fallback"], r["keyframes"], r["loops"], r["reintegrated"],
        cm(r["ate_m"]), cm(r["ate_online_m"]), r["fps"], r["worst_frame_ms"], r["loop_worst_ms"], r["finish_ms"]))
tmp = os.path.join(out, ".tracking.md.tmp")
with open(tmp, "w") as f:
    f.write("\n".join(lines) + "\n")
os.replace(tmp, os.path.join(out, "tracking.md"))
print("\n".join(lines))
EOF
