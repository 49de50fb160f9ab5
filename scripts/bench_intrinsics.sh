#!/usr/bin/env bash
# scripts/bench_intrinsics.sh OUT_DIR INPUTS CAMERAS: the pinhole that fr1's stored images are read with, measured
# (issue 34; bench/results/accuracy/intrinsics.md). Each camera is tracked through the Release `hashfusion run`
# with every other default; writes OUT_DIR/runs/*, OUT_DIR/intrinsics.{md,json} (every run present under OUT_DIR).
#   INPUTS   space-separated: rpy0_149 (choice), rpy150_269 (report), rpy0_269, desk
#   CAMERAS  space-separated FX:CX:CY (fy = fx, 640x480, no distortion; e.g. 532:309.5:250) or a preset name
#            (ros, fr1-registered, ...)
# e.g. HF_BIN=/tmp/hf bash scripts/bench_intrinsics.sh out/intr "rpy0_149" "ros 528:319.5:239.5 532:319.5:239.5"
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/bench_lib.sh
bench_init bench_intrinsics "${1:-out/bench_intrinsics}"
inputs="${2:-rpy0_149}"
cameras="${3:-ros fr1-registered}"

bench_fr1_rpy_0_269  # $work/tum_fr1_rpy_frames0_269
declare -A input_dir=([rpy0_149]="$shared/tum_fr1_rpy_first150" [rpy150_269]="$shared/tum_fr1_rpy_frames150_269"
                      [rpy0_269]="$work/tum_fr1_rpy_frames0_269" [desk]="$shared/tum_fr1_desk_9frames")

for key in $inputs; do
  [[ -n "${input_dir[$key]:-}" ]] || { echo "bench_intrinsics: unknown input '$key'" >&2; exit 1; }
  for cam in $cameras; do
    if [[ "$cam" == *:* ]]; then
      IFS=: read -r fx cx cy <<< "$cam"
      printf 'fx %s\nfy %s\ncx %s\ncy %s\nwidth 640\nheight 480\n' "$fx" "$fx" "$cx" "$cy" > "$work/camera.txt"
      camera="$work/camera.txt"
    else
      camera="$cam"
    fi
    bench_run "${key}__${cam//:/_}" "${input_dir[$key]}" --camera "$camera"
  done
done

bench_ate_table intrinsics camera
