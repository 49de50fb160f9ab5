#!/usr/bin/env bash
# Issue 35 end to end: the last hangs closed (a pose at 1e308, FIFOs given to LiDAR readers) and SIGHUP handled as
# SIGINT / SIGTERM.
#   bash issue35.sh HASHFUSION SCRATCH_DIR CASE
# One CASE per defect (CTest runs each as its own test); each prints why it failed and exits 1. Every command that
# could hang runs under `timeout`, so a regression fails (exit 124) instead of blocking the suite.
set -u
HF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)  # tests/apps, for ../shared beside the repository
ROOT=$2/issue35_$3
CASE=$3
rm -rf "$ROOT" && mkdir -p "$ROOT" && cd "$ROOT" && ROOT=$(pwd) || exit 1
fail() { echo "FAIL ($CASE): $*" >&2; exit 1; }
printf 'fx 131.25\nfy 131.25\ncx 79.5\ncy 59.5\nwidth 160\nheight 120\n' > cam.txt

case "$CASE" in
seven_scenes_far_pose)  # 35.1: a 7-Scenes pose of 1e308 hung `run` in the trajectory plot's tick loops
  "$HF" generate --frames 3 --camera cam.txt --out tum > log 2>&1 || fail "generate failed: $(cat log)"
  mkdir scenes
  n=0
  for f in $(ls tum/rgb | sort); do
    cp "tum/rgb/$f" "scenes/frame-00000$n.color.png"
    cp "tum/depth/$f" "scenes/frame-00000$n.depth.png"
    printf '1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n' > "scenes/frame-00000$n.pose.txt"
    n=$((n + 1))
  done
  printf '1 0 0 1e308\n0 1 0 0\n0 0 1 0\n0 0 0 1\n' > scenes/frame-000001.pose.txt
  timeout 120 "$HF" run --input scenes --camera cam.txt --out out > log 2>&1
  rc=$?
  [ $rc = 1 ] || fail "exit $rc (124 = hung): $(tail -2 log)"
  grep -q "frame-000001.pose.txt:1: expected a translation within 1e6 m (a physical bound), got 1e+308" log ||
    fail "unclear message: $(cat log)"
  [ "$(wc -l < log)" = 1 ] || fail "expected one line: $(cat log)"
  ;;
lidar_fifo)  # 35.2: a FIFO as a LiDAR input or as --footprints blocked forever
  mkfifo f.las f.gpkg
  timeout 60 "$HF" lidar --input f.las --out o > log 2>&1
  rc=$?
  [ $rc = 1 ] || fail "--input FIFO: exit $rc (124 = blocked): $(tail -2 log)"
  grep -q "f.las: cannot read LAS file: it is a FIFO, not a regular file" log || fail "$(cat log)"
  timeout 120 "$HF" lidar --input synthetic:3 --cell-m 2 --footprints f.gpkg --out o2 > log 2>&1
  rc=$?
  [ $rc = 1 ] || fail "--footprints FIFO: exit $rc (124 = blocked): $(tail -2 log)"
  grep -q "f.gpkg: cannot read footprint file: it is a FIFO, not a regular file or a folder" log || fail "$(cat log)"
  ;;
sighup)  # 35.5: SIGHUP (a dropped ssh session) stops after the current frame, writes every output, exits 129
  "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 100000 --out out > log 2>&1 &
  pid=$!
  trap 'kill $pid 2>/dev/null' EXIT  # never leave a 100000-frame run behind
  for _ in $(seq 600); do grep -q "^registration:" log && break; sleep 0.1; done
  sleep 3  # well into the frame loop
  kill -s HUP $pid
  for _ in 1 2 3 4 5; do sleep 0.1; kill -s HUP $pid 2>/dev/null; done  # a second hang-up cannot cut the writing short
  wait $pid
  rc=$?
  [ $rc = 129 ] || fail "exit $rc, expected 129: $(tail -3 log)"
  grep -q "interrupted by SIGHUP: outputs written for [1-9]" log || fail "no final line: $(tail -3 log)"
  for f in trajectory.txt mesh.ply report.json report.md render.png trajectory.png; do
    [ -f "out/$f" ] || fail "missing out/$f"
  done
  grep -q '"interrupted": true' out/report.json || fail "report.json does not say interrupted"
  ;;
transaction)  # 35.5-35.6: outputs replaced as one set; files the previous run did not write survive; a failed run
  # leaves --out as it was; a run killed outright leaves the previous set and a private folder the next run removes
  run_small() { "$HF" run --input synthetic:room --camera cam.txt "$@"; }
  "$HF" generate --frames 3 --camera cam.txt --out nogt > log 2>&1 || fail "generate failed: $(cat log)"
  rm nogt/groundtruth.txt
  # A user's folder: their own trajectory.png and a report.json that is not a run's.
  mkdir user && echo mine > user/trajectory.png && echo '{"notes": 1}' > user/report.json && echo keep > user/notes.txt
  "$HF" run --input nogt --out user > log 2>&1 || fail "run failed: $(cat log)"
  [ "$(cat user/trajectory.png)" = mine ] || fail "the user's trajectory.png was removed or replaced"
  [ "$(cat user/notes.txt)" = keep ] || fail "the user's notes.txt was lost"
  grep -q '"outputs"' user/report.json || fail "report.json is not the run's"
  # A run's own trajectory.png that no longer applies goes; a user's file beside a run's outputs stays.
  run_small --synthetic-frames 3 --out out > log 2>&1 || fail "run failed: $(cat log)"
  [ -f out/trajectory.png ] || fail "the first run (with ground truth) wrote no trajectory.png"
  echo keep > out/notes.txt && mkdir out/sub && echo deep > out/sub/file.txt
  "$HF" run --input nogt --out out > log 2>&1 || fail "run without ground truth failed: $(cat log)"
  [ -e out/trajectory.png ] && fail "the first run's trajectory.png was left beside the second run's outputs"
  [ "$(cat out/notes.txt)" = keep ] && [ "$(cat out/sub/file.txt)" = deep ] || fail "files of the user were lost"
  # A failed run (the pool is full at frame 0) leaves --out as it was, and an absent --out absent.
  before=$(cat out/report.json)
  run_small --synthetic-frames 3 --capacity-blocks 1 --out out > log 2>&1 && fail "a 1-block pool sufficed"
  [ "$(cat out/report.json)" = "$before" ] || fail "a failed run changed report.json"
  run_small --synthetic-frames 3 --capacity-blocks 1 --out fresh > log 2>&1 && fail "a 1-block pool sufficed"
  [ -e fresh ] && fail "a failed run left an --out folder behind: $(ls -A fresh)"
  # SIGKILL mid-run: the previous set stays whole; the next run removes the dead run's private folder.
  "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 100000 --out out > log 2>&1 &
  pid=$!
  trap 'kill -9 $pid 2>/dev/null' EXIT
  for _ in $(seq 600); do grep -q "^registration:" log && break; sleep 0.1; done
  sleep 1
  kill -9 $pid
  wait $pid 2>/dev/null
  [ "$(cat out/report.json)" = "$before" ] || fail "SIGKILL changed the previous outputs"
  ls -A | grep -q '^\.out\.run-' || fail "no private folder of the killed run (was it written in place?)"
  "$HF" run --input nogt --out out > log 2>&1 || fail "run after SIGKILL failed: $(cat log)"
  ls -A | grep -q '^\.out\.run-' && fail "the dead run's private folder was left: $(ls -A)"
  [ "$(cat out/notes.txt)" = keep ] || fail "notes.txt lost after the SIGKILL and rerun"
  ;;
lock)  # 35.7: a second run into a folder in use exits 1 naming the holder's pid
  "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 100000 --out out > log1 2>&1 &
  pid=$!
  trap 'kill $pid 2>/dev/null' EXIT
  for _ in $(seq 600); do grep -q "^registration:" log1 && break; sleep 0.1; done
  "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 3 --out out > log2 2>&1
  rc=$?
  [ $rc = 1 ] || fail "the second run exited $rc: $(tail -2 log2)"
  grep -q "out: in use by another run (pid $pid; lock " log2 || fail "unclear message: $(cat log2)"
  [ "$(wc -l < log2)" = 1 ] || fail "expected one line: $(cat log2)"
  kill -s TERM $pid
  wait $pid
  [ -f out/report.json ] || fail "the first run wrote no outputs after SIGTERM"
  "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 3 --out out > log2 2>&1 ||
    fail "the lock was not released: $(cat log2)"
  ;;
lidar_epsg)  # 35.8: `lidar --epsg -5` was ignored, and an unknown code left the GeoTIFF without a CRS, silently
  for code in -5 999999; do
    timeout 60 "$HF" lidar --input synthetic:3 --cell-m 2 --epsg $code --out o$code > log 2>&1
    rc=$?
    [ $rc = 1 ] || fail "--epsg $code: exit $rc: $(tail -2 log)"
    grep -q -- "--epsg: EPSG:$code is not a coordinate reference system GDAL knows" log || fail "$(cat log)"
    [ "$(wc -l < log)" = 1 ] || fail "expected one line: $(cat log)"
    [ ! -e o$code ] || fail "--epsg $code: the refused run left an output folder"
  done
  ;;
lidar_transaction)  # 35 (build): `lidar`'s outputs as one transaction, like `run`'s
  mkdir o && echo "my notes" > o/notes.txt
  "$HF" lidar --input synthetic:3 --cell-m 2 --out o > log 2>&1 || fail "first run: $(cat log)"
  for f in classes.png classes.tif buildings.png report.json report.md synthetic.las notes.txt; do
    [ -f o/$f ] || fail "o/$f missing after the first run"
  done
  grep -q '"outputs"' o/report.json || fail "report.json lists no outputs"
  grep -q "\"o/synthetic.las\"" o/report.json || fail "report.json names the private folder: $(grep -A2 inputs o/report.json)"
  cp o/report.json first.json
  # A run that fails after the transaction began (its footprints are not a vector file) leaves o as it was.
  echo "not a vector file" > bad.gpkg
  "$HF" lidar --input synthetic:3 --cell-m 2 --footprints bad.gpkg --out o > log 2>&1 && fail "bad footprints: exit 0"
  cmp -s o/report.json first.json || fail "a failed run changed o/report.json"
  [ -f o/classes.png ] || fail "a failed run removed o/classes.png"
  # A second run replaces the run's files, keeps the user's, and leaves no private folder or temporary behind.
  "$HF" lidar --input synthetic:3 --cell-m 3 --out o > log 2>&1 || fail "second run: $(cat log)"
  [ "$(cat o/notes.txt)" = "my notes" ] || fail "the user's notes.txt was lost"
  cmp -s o/report.json first.json && fail "the second run did not replace report.json"
  [ -z "$(ls -A . | grep '^\.o\.run-')" ] || fail "private folders left: $(ls -A .)"
  [ -z "$(find o -name '*.tmp*')" ] || fail "temporaries left: $(find o -name '*.tmp*')"
  ;;
bench_transaction)  # 35 (build): `bench`'s outputs as one transaction, like `run`'s
  mkdir o && echo "my notes" > o/notes.txt
  "$HF" bench --input synthetic:wall --synthetic-frames 3 --registration icp --peers none --out o > log 2>&1 ||
    fail "first bench: $(cat log)"
  for f in results.md results.json results.csv speed_vs_error.png notes.txt; do
    [ -f o/$f ] || fail "o/$f missing after the first bench"
  done
  grep -q "$ROOT/o/results.md" log || fail "the outputs listed are not where they ended up: $(cat log)"
  cp o/results.json first.json
  # A bench that fails after the transaction began (its input does not exist) leaves o as it was.
  "$HF" bench --input no_such_folder --registration icp --peers none --out o > log 2>&1 && fail "missing input: exit 0"
  cmp -s o/results.json first.json || fail "a failed bench changed o/results.json"
  # --merge into the same folder replaces the run's files and keeps the user's.
  "$HF" bench --merge o --out o > log 2>&1 || fail "merge into o: $(cat log)"
  [ "$(cat o/notes.txt)" = "my notes" ] || fail "the user's notes.txt was lost"
  [ -f o/results.md ] || fail "merge wrote no results.md"
  [ -z "$(ls -A . | grep '^\.o\.run-')" ] || fail "private folders left: $(ls -A .)"
  ;;
head_transaction)  # 35 (build): `head-features`'s outputs as one transaction, like `run`'s
  mesh="$HERE/../../../shared/data/head_meshes/libigl_face_head.obj"
  [ -f "$mesh" ] || { echo "skipped: $mesh not found (../shared absent)"; exit 0; }
  mkdir o && echo "my notes" > o/notes.txt
  "$HF" head-features --mesh "$mesh" --out o > log 2>&1 || fail "first run: $(cat log)"
  [ -f o/report.md ] || fail "no report.md"
  cp o/report.md first.md
  # A run that fails after reading (an unknown method) leaves o as it was.
  "$HF" head-features --mesh "$mesh" --method bogus --out o > log 2>&1 && fail "bogus method: exit 0"
  cmp -s o/report.md first.md || fail "a failed run changed o/report.md"
  "$HF" head-features --mesh "$mesh" --out o > log 2>&1 || fail "second run: $(cat log)"
  [ "$(cat o/notes.txt)" = "my notes" ] || fail "the user's notes.txt was lost"
  [ -z "$(ls -A . | grep '^\.o\.run-')" ] || fail "private folders left: $(ls -A .)"
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "ok ($CASE)"
