#!/usr/bin/env bash
# scripts/bench_accuracy.sh OUT_DIR [distortion] [depth_only]: issue 34's accuracy measurements with the Release
# `hashfusion run` (defaults otherwise). Writes OUT_DIR/runs/* and OUT_DIR/accuracy.{md,json} (every run present).
#   distortion  TUM fr1/rpy 0-149 (choice), 150-269 (report), 0-269 (the two joined) and fr1/desk, each read with
#               the ROS intrinsics as before (ros), with the fr1 intrinsics as a pinhole (fr1_pinhole) and with the fr1
#               intrinsics and lens distortion, undistorted on arrival (fr1_undistorted, --camera fr1).
#   depth_only  7-Scenes 0-99 (choice), 100-199 (report) and 0-199: the colour check's hand-over target icp or sdf,
#               with all depth or depth cut at 3 / 4 m (pyramid and integration).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/bench_lib.sh
bench_init bench_accuracy "${1:-out/bench_accuracy}"
shift || true
parts=("$@")
[[ ${#parts[@]} -gt 0 ]] || parts=(distortion depth_only)

bench_fr1_rpy_0_269        # $work/tum_fr1_rpy_frames0_269
joined="$work/tum_fr1_rpy_frames0_269"
bench_seven_scenes_halves  # $work/7scenes_frames0_99, $work/7scenes_frames100_199
seven="$(realpath "$shared/7scenes_tsdf_fusion_first200")"
printf 'fx 517.3\nfy 516.5\ncx 318.6\ncy 255.3\nwidth 640\nheight 480\n' > "$work/fr1_pinhole.txt"

for part in "${parts[@]}"; do
  case "$part" in
    distortion)
      declare -A tum=([rpy0_149]="$shared/tum_fr1_rpy_first150" [rpy150_269]="$shared/tum_fr1_rpy_frames150_269"
                      [rpy0_269]="$joined" [desk]="$shared/tum_fr1_desk_9frames")
      declare -A camera=([ros]=ros [fr1_pinhole]="$work/fr1_pinhole.txt" [fr1_undistorted]=fr1)
      for key in ${DISTORTION_INPUTS:-rpy0_149 rpy150_269 rpy0_269 desk}; do
        input="${tum[$key]}"
        name="$(bench_input_name "$input")"
        for mode in ${DISTORTION_MODES:-ros fr1_pinhole fr1_undistorted}; do
          bench_run "${name}__${mode}" "$input" --camera "${camera[$mode]}"
        done
      done ;;
    depth_only)
      declare -A seven_part=([0_99]="$work/7scenes_frames0_99" [100_199]="$work/7scenes_frames100_199" [0_199]="$seven")
      for key in ${DEPTH_ONLY_INPUTS:-0_99 100_199 0_199}; do
        input="${seven_part[$key]}"
        name="$(bench_input_name "$input")"
        for mode in ${DEPTH_ONLY_MODES:-icp:0 icp:3 icp:4 sdf:0 sdf:3 sdf:4}; do
          method="${mode%%:*}" range="${mode##*:}"
          if [[ "$range" == 0 ]]; then
            echo "{\"colour_check\": {\"depth_only_registration\": \"$method\"}}" > "$work/c.json"
          else
            echo "{\"colour_check\": {\"depth_only_registration\": \"$method\"}, \"pyramid\": {\"max_depth_m\": $range}," \
                 "\"integrate\": {\"max_depth_m\": $range}}" > "$work/c.json"
          fi
          bench_run "${name}__${method}_max${range}m" "$input" --config "$work/c.json"
        done
      done ;;
    *) echo "bench_accuracy: unknown part '$part' (distortion, depth_only)" >&2; exit 1 ;;
  esac
done

python3 - "$out" <<'PY'
import json, os, sys
sys.path.insert(0, "scripts")
from bench_runs import runs  # noqa: E402
out = sys.argv[1]
rows = []
for name, mode, j in runs(out):
    ms = j["ms_per_frame"]
    rows.append({"input": name, "mode": mode, "frames": j["frames"], "lost": j["frames_lost"],
                 "ate_cm": None if j["ate_rmse_m"] is None else 100 * j["ate_rmse_m"],
                 "tracking": j.get("colour_check", {}).get("tracking_registration"),
                 "preprocess_ms": ms["preprocess"], "track_ms": ms["track"], "fps": j["fps"]})
json.dump(rows, open(os.path.join(out, "accuracy.json"), "w"), indent=1)
f = lambda v, p=2: "-" if v is None else f"{v:.{p}f}"
with open(os.path.join(out, "accuracy.md"), "w") as md:
    md.write("| input | mode | frames | lost | tracked by | ATE cm | preprocess ms | track ms | fps |\n"
             "|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        md.write(f"| {r['input']} | {r['mode']} | {r['frames']} | {r['lost']} | {r['tracking']} | {f(r['ate_cm'])} | "
                 f"{f(r['preprocess_ms'], 1)} | {f(r['track_ms'], 1)} | {f(r['fps'], 1)} |\n")
print(open(os.path.join(out, "accuracy.md")).read())
PY
