#!/usr/bin/env bash
# The measurements of bench/results/cluster.md (issue 37): scripts/lidar_tiles.slurm and scripts/bench_sweep.slurm
# under a private single-node Slurm cluster on this machine (tests/scripts/slurm_cluster.sh), every hashfusion
# process wrapped in /usr/bin/time (wall seconds, peak RSS).
#
#   bash bench/cluster_scaling.sh BUILD_DIR WORK_DIR > bench/results/cluster.raw.txt
#
# 1. LiDAR as 1, 2 and 6 array tasks (tiles 1x1, 2x1, 3x2): the AHN3 Delft crop with its footprints, and a larger
#    survey (6 x 6 copies of the synthetic settlements, scripts/lidar_replicate_las.py) where the work outweighs
#    the scheduler's dispatch. Per configuration: submission to the merge's end (wall), each task's and the merge's
#    own wall time and peak RSS. A single run without Slurm for reference.
# 2. A bench sweep (synthetic:room and TUM fr1/rpy 0-149, icp / combined, 100 and 150 frames): each run's
#    peak RSS and wall time, and the merge's.
set -euo pipefail
build=$(cd "$1" && pwd)
work=$2
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
hf=$build/apps/hashfusion
shared=$src/../shared/data
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)
state=$work/cluster
bash "$src/tests/scripts/slurm_cluster.sh" start "$state"
trap 'bash "$src/tests/scripts/slurm_cluster.sh" stop "$state"' EXIT
source "$state/env"

# The wrapper every job runs instead of hashfusion: one line per process in $HF_TIME_LOG.
cat > "$work/hf-timed" <<EOF
#!/bin/bash
exec /usr/bin/time -f "%e s wall, %U+%S s CPU, %M KiB: \$*" -a -o "\$HF_TIME_LOG" "$hf" "\$@"
EOF
chmod +x "$work/hf-timed"

wait_for_job() {
  srun --quiet --dependency=afterany:"$1" --mem=16M --job-name=hf-wait true
}
job_field() { scontrol show job -o "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n 1; }

echo "# $(date -u +%FT%TZ), commit $(git -C "$src" rev-parse --short HEAD), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"

lidar_case() {  # lidar_case NAME INPUT ARGS
  local name=$1 input=$2 args=$3 tiles n out t0 t1 ids a m
  /usr/bin/time -f "%e s wall, %U+%S s CPU, %M KiB: single run" -o "$work/$name-single.time" \
    "$hf" lidar --input "$input" --out "$work/$name-single" $args > /dev/null
  echo "$name single run (no Slurm): $(cat "$work/$name-single.time")"
  for tiles in 1,1 2,1 3,2; do
    n=$(( ${tiles%,*} * ${tiles#*,} ))
    out=$work/$name-$n
    export HF_TIME_LOG=$work/$name-$n.time
    t0=$(date +%s.%N)
    ids=$(HASHFUSION=$work/hf-timed HF_INPUTS="$input" HF_OUT="$out" HF_TILES=$tiles HF_ARGS="$args" \
          bash "$src/scripts/lidar_tiles.slurm" submit)
    read -r a m < <(sed -n 's/^array job \([0-9]*\) .*merge job \([0-9]*\) after it.*/\1 \2/p' <<< "$ids")
    wait_for_job "$m"
    t1=$(date +%s.%N)
    for f in classes.png classes.tif buildings.png; do
      [[ ! -f $work/$name-single/$f ]] || cmp -s "$work/$name-single/$f" "$out/$f" || echo "  $f DIFFERS"
    done
    echo "$name as $n array tasks (tiles $tiles): merge $(job_field "$m" JobState); submission to the waiter's return $(awk "BEGIN { printf \"%.1f\", $t1 - $t0 }") s;" \
         "array $(job_field "${a}_0" SubmitTime) .. merge end $(job_field "$m" EndTime)"
    sed 's/^/  /' "$HF_TIME_LOG"
  done
}

delft=$shared/lidar_ahn3_delft
lidar_case delft "$delft/ahn3_cropped_2.las" \
  "--cell-m 0.5 --t 2 --epsg 28992 --footprints $delft/bgt_pand.sqlite --footprint-layer buildingpart"
"$hf" lidar --input synthetic:1 --cell-m 1 --out "$work/s1" > /dev/null
/usr/bin/python3 "$src/scripts/lidar_replicate_las.py" "$work/s1/synthetic.las" "$work/survey.las" 6 6
lidar_case survey "$work/survey.las" "--cell-m 1 --areas 1500,10000,35000 --t 2 --max-height-m 10 --max-building-m 20"

# The bench sweep: per run memory and time.
export HF_TIME_LOG=$work/sweep.time
args="--registration icp,combined --peers none --synthetic-frames 100"
t0=$(date +%s.%N)
ids=$(HASHFUSION=$work/hf-timed HF_INPUTS="synthetic:room $shared/tum_fr1_rpy_first150" HF_OUT="$work/sweep" \
      HF_ARGS="$args" HF_CPUS=1 bash "$src/scripts/bench_sweep.slurm" submit)
read -r a m < <(sed -n 's/^array job \([0-9]*\) .*merge job \([0-9]*\) after it.*/\1 \2/p' <<< "$ids")
wait_for_job "$m"
t1=$(date +%s.%N)
echo "bench sweep (2 inputs x 2 methods, 4 tasks): merge $(job_field "$m" JobState); submission to the waiter's return $(awk "BEGIN { printf \"%.1f\", $t1 - $t0 }") s"
sed 's/^/  /' "$HF_TIME_LOG"
echo "# load at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
