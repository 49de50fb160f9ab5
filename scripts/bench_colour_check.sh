#!/usr/bin/env bash
# scripts/bench_colour_check.sh OUT_DIR: the colour-registration check (issue 13, slam/colour_check.h) on every real
# sequence in ../shared/data (whole, and split where the threshold was chosen on one part: fr1/rpy 0-149 and
# 7-Scenes 0-99 chose it; fr1/rpy 150-269, fr1/desk and 7-Scenes 100-199 report it) and on the synthetic room /
# unregistered presets, each with the check on (the default) and off. Release `hashfusion run`, defaults otherwise.
# Writes OUT_DIR/colour_check.{md,json}.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/bench_lib.sh
bench_init bench_colour_check "${1:-out/bench_colour_check}"
bench_seven_scenes_halves  # $work/7scenes_frames0_99, $work/7scenes_frames100_199
seven="$(realpath "$shared/7scenes_tsdf_fusion_first200")"
echo '{"colour_check": {"enabled": false}}' > "$work/off.json"
inputs=(
  "$shared/tum_fr1_rpy_first150" "$shared/tum_fr1_rpy_frames150_269" "$shared/tum_fr1_desk_9frames"
  "$work/7scenes_frames0_99" "$work/7scenes_frames100_199" "$seven" "synthetic:room" "synthetic:unregistered"
)
for input in "${inputs[@]}"; do
  name="$(bench_input_name "$input")"
  frames=()
  [[ "$name" == synthetic_* ]] && frames=(--synthetic-frames 120)
  bench_run "${name}__on" "$input" "${frames[@]}"
  bench_run "${name}__off" "$input" "${frames[@]}" --config "$work/off.json"
done

python3 - "$out" <<'PY'
import json, os, statistics, sys
sys.path.insert(0, "scripts")
from bench_runs import runs  # noqa: E402
out = sys.argv[1]
rows = []
for name, mode, j in runs(out):
    scales = [f["colour_alignment"]["scale"] for f in j["per_frame"]
              if f.get("colour_alignment", {}).get("valid")]
    chi2 = [f["terms"]["chi2"] for f in j["per_frame"] if "terms" in f]
    cc = j["colour_check"]
    rows.append({"input": name, "check": mode, "frames": j["frames"], "lost": j["frames_lost"],
                 "verdict": cc["verdict"], "median_scale": cc["median_scale"],
                 "decided_at_frame": cc["decided_at_frame"], "tracking": cc["tracking_registration"],
                 "estimates": len(scales), "scale_min": min(scales) if scales else None,
                 "scale_max": max(scales) if scales else None,
                 "terms_chi2_median": statistics.median(chi2) if chi2 else None,
                 "ate_cm": 100 * j["ate_rmse_m"] if j["ate_rmse_m"] is not None else None,
                 "track_ms": j["ms_per_frame"]["track"], "fps": j["fps"]})
json.dump(rows, open(os.path.join(out, "colour_check.json"), "w"), indent=1)
f = lambda v, p=2: "-" if v is None else f"{v:.{p}f}"
with open(os.path.join(out, "colour_check.md"), "w") as md:
    md.write("| input | check | frames | lost | verdict | median s (min-max of the estimates) | decided at | tracked by"
             " | combined's terms chi2 (median) | ATE cm | track ms | fps |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        md.write(f"| {r['input']} | {r['check']} | {r['frames']} | {r['lost']} | {r['verdict']} | "
                 f"{f(r['median_scale'], 3)} ({f(r['scale_min'], 3)}-{f(r['scale_max'], 3)}) | "
                 f"{'-' if r['decided_at_frame'] is None else r['decided_at_frame']} | {r['tracking']} | "
                 f"{f(r['terms_chi2_median'], 0)} | {f(r['ate_cm'])} | {f(r['track_ms'], 1)} | {f(r['fps'], 1)} |\n")
print(open(os.path.join(out, "colour_check.md")).read())
PY
