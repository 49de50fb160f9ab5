#!/usr/bin/env bash
# Reproduces bench/results/table1 (issue 17: the report's Table 1 over every registry method and the PCL peers):
# hashfusion bench on every synthetic preset and every TUM / 7-Scenes folder of ../shared/data, FRAMES frames each.
#
#   bash bench/table1.sh [OUT]      # OUT defaults to out/table1; FRAMES=30, HASHFUSION=build/release/apps/hashfusion
#
# Writes OUT/results.{md,json,csv} and the speed-vs-error plots; copy them into bench/results/table1/ to update it.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-out/table1}
frames=${FRAMES:-30}
hashfusion=${HASHFUSION:-$root/build/release/apps/hashfusion}
data=${HF_SHARED_DIR:-$root/../shared}/data
inputs=(synthetic:all)
for d in tum_fr1_rpy_first150 tum_fr1_rpy_frames150_269 tum_fr1_desk_9frames 7scenes_tsdf_fusion_first200; do
  if [ -d "$data/$d" ]; then inputs+=("$data/$d"); else echo "table1: $data/$d missing, left out" >&2; fi
done
[ -x "$hashfusion" ] || { echo "table1: $hashfusion not built (cmake --build --preset release --target hashfusion)" >&2; exit 1; }
exec "$hashfusion" bench --registration all --peers all --max-frames "$frames" --synthetic-frames "$frames" \
  --out "$out" --input "${inputs[@]}"
