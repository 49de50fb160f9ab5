#!/usr/bin/env bash
# scripts/lidar_tiles.slurm and scripts/bench_sweep.slurm submitted to the private cluster of slurm_cluster.sh
# (the CTest fixture hf_slurm_cluster, issue 37), checked against single runs of the same commands.
#
#   slurm_jobs.sh CASE STATE HASHFUSION SOURCE_DIR WORK_DIR CMAKE
#   lidar_tiles: 3x2 tiles of the synthetic settlements, the AHN3 Delft crop (with its BGT footprints) and PDAL's
#                sample_c.las as job arrays, each merged by a job that depends on its array: classes.png,
#                classes.tif, buildings.png byte-identical to the single run, report.json's classes equal.
#   lidar_fault: tile 4 of 6 fails (HF_FAULT_INDEX=4): that task FAILED with its reason in its log, the other five
#                COMPLETED, the merge CANCELLED by its dependency and no raster written; re-submitting index 4
#                alone (HF_ARRAY=4) completes the run, byte-identical to the single run.
#   bench_sweep: `hashfusion bench` over 2 inputs x 3 methods as a 6-task array (one run per task, each task
#                given 1 CPU but unbound: TBB uses both cores) and `bench --merge` after it, against one single run
#                pinned to one core (taskset): methods, inputs and every accuracy field equal exactly, and the
#                won-lost-tie tables by ATE and by RPE (compare_bench_results.cmake). 12 frames keep it short
#                (0.4 s: the RPE per frame pair exists, the RPE over 1 s is null on both sides).
# Exit 77 (CTest skip) when the cluster fixture did not start one (no slurm-wlm / munge outside CI).
set -euo pipefail
case=$1 state=$2 hf=$3 src=$4 work=$5 cmake=$6
if [[ ! -f $state/env ]]; then
  echo "slurm $case: skipped: no private Slurm cluster (slurm_cluster_start skipped: slurm-wlm or munge missing)"
  exit 77
fi
source "$state/env"
shared=$src/../shared/data
rm -rf "$work"
mkdir -p "$work"
cd "$work"

fail() { echo "slurm $case: $*" >&2; exit 1; }
run() { "$@" > "$work/last.log" 2>&1 || { cat "$work/last.log" >&2; fail "$* failed"; }; }

# Waits for job $1 to end (in any state) with a dependent no-op step: Slurm's dependency, not a polling loop.
# srun hears of its allocation at once (sbatch --wait polls, up to 30 s late).
wait_for_job() {
  timeout 300 srun --quiet --dependency=afterany:"$1" --mem=16M --time=1 --job-name=hf-wait true ||
    fail "job $1 did not end within 300 s: $(squeue -h 2>&1)"
}
job_field() {  # job_field JOBID FIELD: JobState, Reason, ExitCode of a job (MinJobAge keeps it 10 minutes)
  scontrol show job -o "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n 1
}
submitted_ids() {  # "array job A (...), merge job M after it; ..." -> "A M"
  sed -n 's/^array job \([0-9]*\) .*merge job \([0-9]*\) after it.*/\1 \2/p' <<< "$1"
}
same_bytes() {  # same_bytes SINGLE MERGED: the merged rasters equal the single run's, byte for byte
  local f
  for f in classes.png classes.tif buildings.png; do
    [[ -f $1/$f ]] || continue
    [[ -f $2/$f ]] || fail "$2/$f: not written"
    cmp -s "$1/$f" "$2/$f" || fail "$f: the merged tiles ($2) differ from the single run ($1)"
  done
  for f in hamlet village town city; do
    local a b
    a=$("$cmake" -DFILE="$1/report.json" -DKEY="classes;$f" -P "$src/tests/scripts/json_get.cmake" 2>&1)
    b=$("$cmake" -DFILE="$2/report.json" -DKEY="classes;$f" -P "$src/tests/scripts/json_get.cmake" 2>&1)
    [[ $a == "$b" ]] || fail "report.json classes.$f: single '$a', merged '$b'"
  done
}
lidar_submit() {  # lidar_submit NAME INPUTS ARGS [ENV...]: submits scripts/lidar_tiles.slurm, prints "ARRAY MERGE"
  local name=$1 inputs=$2 args=$3 out
  shift 3
  out=$(env "$@" HASHFUSION="$hf" HF_INPUTS="$inputs" HF_OUT="$work/$name" HF_TILES=3,2 HF_ARGS="$args" \
        bash "$src/scripts/lidar_tiles.slurm" submit) || fail "lidar_tiles.slurm submit ($name): $out"
  echo "$out" >&2
  submitted_ids "$out"
}

synthetic_args="--cell-m 1 --areas 1500,10000,35000 --t 2 --max-height-m 10 --max-building-m 20"
synthetic_las() {  # the synthetic settlements (seed 3) and their single run, as tests/lidar/lidar_tiles_cli.cmake
  run "$hf" lidar --input synthetic:3 --out "$work/single_synthetic" $synthetic_args
  [[ -f $work/single_synthetic/synthetic.las ]] || fail "no synthetic.las written"
}

case $case in
  lidar_tiles)
    synthetic_las
    declare -A jobs
    ids=$(lidar_submit synthetic "$work/single_synthetic/synthetic.las" "$synthetic_args")
    read -r a m <<< "$ids"
    jobs[synthetic]="$a $m"
    delft=$shared/lidar_ahn3_delft
    pdal=$shared/lidar_pdal_sample_c/sample_c.las
    delft_args="--cell-m 0.5 --t 2 --epsg 28992 --footprints $delft/bgt_pand.sqlite --footprint-layer buildingpart"
    pdal_args="--cell-m 0.5 --t 2"
    if [[ -f $delft/ahn3_cropped_2.las && -f $pdal ]]; then
      ids=$(lidar_submit delft "$delft/ahn3_cropped_2.las" "$delft_args")
      read -r a m <<< "$ids"
      jobs[delft]="$a $m"
      ids=$(lidar_submit pdal "$pdal" "$pdal_args")
      read -r a m <<< "$ids"
      jobs[pdal]="$a $m"
      # The single runs while the cluster works.
      run "$hf" lidar --input "$delft/ahn3_cropped_2.las" --out "$work/single_delft" $delft_args
      run "$hf" lidar --input "$pdal" --out "$work/single_pdal" $pdal_args
    else
      echo "slurm lidar_tiles: $shared (Delft / PDAL LAS files) absent: only the synthetic settlements"
    fi
    for name in "${!jobs[@]}"; do
      read -r a m <<< "${jobs[$name]}"
      wait_for_job "$m"
      st=$(job_field "$m" JobState)
      [[ $st == COMPLETED ]] || fail "$name: merge job $m $st ($(job_field "$m" Reason)); logs: $(tail -n 3 "$work/$name"/logs/*.log)"
      for k in 0 1 2 3 4 5; do
        [[ $(job_field "${a}_$k" JobState) == COMPLETED ]] || fail "$name: task ${a}_$k $(job_field "${a}_$k" JobState)"
        [[ -f $work/$name/logs/hf-lidar-${a}_$k.log ]] || fail "$name: no log for task $k"
      done
      [[ $(ls "$work/$name/tiles"/tile_*.hflt | wc -l) == 6 ]] || fail "$name: expected 6 tile files"
      same_bytes "$work/single_$name" "$work/$name"
      echo "slurm lidar_tiles: $name: 6 tiles (array job $a) merged by job $m after it, byte-identical to the single run"
    done
    ;;

  lidar_fault)
    synthetic_las
    ids=$(lidar_submit fault "$work/single_synthetic/synthetic.las" "$synthetic_args" HF_FAULT_INDEX=4)
    read -r a m <<< "$ids"
    wait_for_job "$m"
    [[ $(job_field "${a}_4" JobState) == FAILED ]] || fail "task ${a}_4: $(job_field "${a}_4" JobState), expected FAILED"
    grep -q "tile 4: failed on purpose" "$work/fault/logs/hf-lidar-${a}_4.log" || fail "task 4's log does not say why it failed"
    for k in 0 1 2 3 5; do
      [[ $(job_field "${a}_$k" JobState) == COMPLETED ]] || fail "task ${a}_$k: $(job_field "${a}_$k" JobState)"
    done
    st=$(job_field "$m" JobState) reason=$(job_field "$m" Reason)
    [[ $st == CANCELLED && $reason == DependencyNeverSatisfied ]] || fail "merge job $m: $st ($reason), expected CANCELLED (DependencyNeverSatisfied)"
    [[ ! -e $work/fault/classes.png && ! -e $work/fault/tiles/tile_4.hflt ]] || fail "the merge ran or tile 4 was written"
    echo "slurm lidar_fault: task ${a}_4 FAILED, the other five COMPLETED, merge $m CANCELLED ($reason)"
    # The user's recovery: the same environment, only the failed index (and without the fault).
    ids=$(lidar_submit fault "$work/single_synthetic/synthetic.las" "$synthetic_args" HF_ARRAY=4)
    read -r a2 m2 <<< "$ids"
    wait_for_job "$m2"
    [[ $(job_field "${a2}_4" JobState) == COMPLETED ]] || fail "re-submitted task ${a2}_4: $(job_field "${a2}_4" JobState)"
    [[ $(job_field "$m2" JobState) == COMPLETED ]] || fail "merge $m2 after the re-submission: $(job_field "$m2" JobState)"
    same_bytes "$work/single_synthetic" "$work/fault"
    echo "slurm lidar_fault: HF_ARRAY=4 re-submitted tile 4 (job ${a2}_4); merge $m2 completed, byte-identical"
    ;;

  bench_sweep)
    inputs="synthetic:wall synthetic:room"
    args="--registration icp,combined,gicp --peers none --synthetic-frames 12 --max-frames 12"
    runs=$("$hf" bench --input synthetic:wall --input synthetic:room $args --list-runs)
    [[ $(grep -c . <<< "$runs") == 6 ]] || fail "bench --list-runs: expected 6 runs, got: $runs"
    out=$(HASHFUSION="$hf" HF_INPUTS="$inputs" HF_OUT="$work/sweep" HF_ARGS="$args" HF_CPUS=1 \
          bash "$src/scripts/bench_sweep.slurm" submit) || fail "bench_sweep.slurm submit: $out"
    echo "$out"
    read -r a m <<< "$(submitted_ids "$out")"
    # The single run pinned to one core (one TBB thread) while the array runs unpinned: the tables must not
    # depend on the thread count.
    run taskset -c 0 "$hf" bench --input synthetic:wall --input synthetic:room $args --out "$work/single"
    wait_for_job "$m"
    st=$(job_field "$m" JobState)
    [[ $st == COMPLETED ]] || fail "merge job $m: $st; $(tail -n 5 "$work"/sweep/logs/*.log)"
    for k in 0 1 2 3 4 5; do
      [[ $(job_field "${a}_$k" JobState) == COMPLETED ]] || fail "task ${a}_$k: $(job_field "${a}_$k" JobState)"
      [[ -f $work/sweep/parts/$k/results.json ]] || fail "task $k wrote no part"
    done
    "$cmake" -DSINGLE="$work/single/results.json" -DMERGED="$work/sweep/results.json" \
      -P "$src/tests/scripts/compare_bench_results.cmake" || fail "the merged sweep differs from the single run"
    echo "slurm bench_sweep: 6 tasks (array job $a) merged by job $m equal the single run's tables"
    ;;
  *) fail "unknown case" ;;
esac
