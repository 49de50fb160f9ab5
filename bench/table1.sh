#!/usr/bin/env bash
# Reproduces bench/results/table1 (issue 17: the report's Table 1 over every registry method and the peers):
# hashfusion bench on every synthetic preset and every TUM / 7-Scenes folder of ../shared/data.
#
#   bash bench/table1.sh [OUT]      # OUT defaults to out/table1
#
# FRAMES (default 0: every frame of each real folder: 150 / 120 / 9 / 200) and SYNTHETIC_FRAMES (default 45: 1.5 s
# at 30 Hz, so every synthetic run has an RPE over 1 s) set the lengths; PEERS (default all: PCL's gicp / ndt and,
# where the build found Open3D, o3d-icp / o3d-colored-icp / o3d-rgbd); HASHFUSION=build/release/apps/hashfusion.
# Writes OUT/results.{md,json,csv} and the speed-vs-error plots; copy them into bench/results/table1/ to update it.
# Rows of one method re-run later go in with `hashfusion bench --merge OLD NEW --out MERGED`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-out/table1}
frames=${FRAMES:-0}
synthetic_frames=${SYNTHETIC_FRAMES:-45}
peers=${PEERS:-all}
registration=${REGISTRATION:-all}
hashfusion=${HASHFUSION:-$root/build/release/apps/hashfusion}
data=${HF_SHARED_DIR:-$root/../shared}/data
inputs=()
for d in tum_fr1_rpy_first150 tum_fr1_rpy_frames150_269 tum_fr1_desk_9frames 7scenes_tsdf_fusion_first200; do
  if [ -d "$data/$d" ]; then inputs+=("$data/$d"); else echo "table1: $data/$d missing, left out" >&2; fi
done
inputs+=(synthetic:all)  # after the real folders: an interrupted run (SIGTERM writes what finished) keeps them
[ -x "$hashfusion" ] || { echo "table1: $hashfusion not built (cmake --build --preset release --target hashfusion)" >&2; exit 1; }
# Open3D's peers single-threaded, as PCL's: OpenMP's spinning threads on a loaded machine made o3d-rgbd ~4x slower.
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
exec "$hashfusion" bench --registration "$registration" --peers "$peers" --max-frames "$frames" \
  --synthetic-frames "$synthetic_frames" --out "$out" --input "${inputs[@]}"
