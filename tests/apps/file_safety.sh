#!/usr/bin/env bash
# Issue 14 end to end: files in and out that never lose data and never trust the file system.
#   bash file_safety.sh HASHFUSION SCRATCH_DIR CASE
# One CASE per defect of the issue (CTest runs each as its own test); each prints why it failed and exits 1.
set -u
HF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")  # absolute: the cases cd into their scratch folder
ROOT=$2/file_safety_$3
CASE=$3
rm -rf "$ROOT" && mkdir -p "$ROOT" && cd "$ROOT" && ROOT=$(pwd) || exit 1
fail() { echo "FAIL ($CASE): $*" >&2; exit 1; }
# A 160x120 camera keeps every run short, under ASan too.
printf 'fx 131.25\nfy 131.25\ncx 79.5\ncy 59.5\nwidth 160\nheight 120\n' > cam.txt
run_small() { "$HF" run --input synthetic:room --camera cam.txt "$@"; }
outputs="trajectory.txt mesh.ply report.json report.md render.png trajectory.png"
expect_outputs() {
  for f in $outputs; do [ -f "$1/$f" ] && [ ! -L "$1/$f" ] || fail "missing or not a regular file: $1/$f"; done
}

case "$CASE" in
symlink)  # 14.1: a link planted at the old predictable temporary name, and one at an output, are not followed
  echo victim > victim.txt
  echo victim > victim2.txt
  mkdir out
  ln -s "$ROOT/victim2.txt" out/report.json
  bash -c 'ln -s "$1/victim.txt" "$1/out/trajectory.tmp$$.txt"; exec "$2" run --input synthetic:room --camera "$1/cam.txt" --synthetic-frames 3 --out "$1/out"' \
    _ "$ROOT" "$HF" > log 2>&1 || fail "run failed: $(cat log)"
  [ "$(cat victim.txt)" = victim ] || fail "victim.txt was overwritten through the planted link"
  [ "$(cat victim2.txt)" = victim ] || fail "victim2.txt was overwritten through out/report.json"
  expect_outputs out
  ;;
generate)  # 14.2: generate deletes only what a previous generate wrote
  mkdir -p some/dir && echo keep > some/dir/precious.txt
  (cd some/dir && "$HF" generate --frames 2 --camera ../../cam.txt --out . --force) > log 2>&1 && fail "--out . --force succeeded"
  grep -q "refusing to replace" log || fail "no refusal message: $(cat log)"
  [ -f some/dir/precious.txt ] || fail "--out . --force deleted the folder's contents"
  mkdir results.tmp && echo mine > results.tmp/notes.txt
  "$HF" generate --frames 2 --camera cam.txt --out results > log 2>&1 || fail "generate failed: $(cat log)"
  "$HF" generate --frames 3 --camera cam.txt --out results --force > log 2>&1 || fail "generate --force failed: $(cat log)"
  [ -f results.tmp/notes.txt ] || fail "an unrelated results.tmp was removed"
  [ "$(ls results/rgb | wc -l)" = 3 ] || fail "the replaced output does not hold the new 3 frames"
  "$HF" generate --frames 2 --camera cam.txt --out some/dir --force > log 2>&1 && fail "replaced a folder that is not ours"
  grep -q "does not look like an output of hashfusion generate" log || fail "unclear refusal: $(cat log)"
  [ -z "$(ls -A . | grep -v -e '^cam.txt$' -e '^log$' -e '^results$' -e '^results.tmp$' -e '^some$')" ] ||
    fail "left behind: $(ls -A .)"
  ;;
out_check)  # 14.3: an unusable --out is reported before the first frame
  touch afile
  for out in afile afile/sub /proc/self; do
    [ "$out" = /proc/self ] && [ ! -d /proc/self ] && continue
    run_small --synthetic-frames 3 --out "$out" > log 2>&1 && fail "run --out $out succeeded"
    grep -q "^input:" log && fail "run --out $out processed the input before checking --out: $(cat log)"
    [ "$(wc -l < log)" = 1 ] || fail "expected one error line for --out $out: $(cat log)"
  done
  ;;
stale_outputs)  # 14.4: a second run into the same --out leaves none of the first run's files that no longer apply
  run_small --synthetic-frames 3 --out out > log 2>&1 || fail "run failed: $(cat log)"
  [ -f out/trajectory.png ] || fail "the first run (with ground truth) wrote no trajectory.png"
  "$HF" generate --frames 3 --camera cam.txt --out nogt > log 2>&1 || fail "generate failed: $(cat log)"
  rm nogt/groundtruth.txt
  "$HF" run --input nogt --out out > log 2>&1 || fail "run without ground truth failed: $(cat log)"
  [ -e out/trajectory.png ] && fail "the first run's trajectory.png was left beside the second run's outputs"
  grep -q '"outputs"' out/report.json || fail "report.json does not record its set of outputs"
  grep -A8 '"outputs"' out/report.json | grep -q trajectory.png && fail "report.json lists trajectory.png"
  ;;
signals)  # 14.5: SIGTERM as SIGINT, a second signal cannot cut the writing short, exit 130 / 143 after writing
  for sig in TERM INT; do
    rm -rf "out_$sig" "log_$sig"
    # Started directly, not through a shell function, so $! is hashfusion's own pid.
    "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 100000 --out "out_$sig" > "log_$sig" 2>&1 &
    pid=$!
    trap 'kill $pid 2>/dev/null' EXIT  # never leave a 100000-frame run behind
    for _ in $(seq 600); do grep -q "^registration:" "log_$sig" && break; sleep 0.1; done
    sleep 3  # well into the frame loop (160x120 frames take milliseconds, tens under ASan)
    kill -s "$sig" $pid
    for _ in 1 2 3 4 5 6 7 8 9 10; do sleep 0.1; kill -s INT $pid 2>/dev/null; done  # impatient Ctrl-C while writing
    wait $pid
    rc=$?
    want=$([ $sig = TERM ] && echo 143 || echo 130)
    [ $rc = "$want" ] || fail "SIG$sig: exit $rc, expected $want: $(tail -3 "log_$sig")"
    grep -q "interrupted by SIG$sig: outputs written for [1-9]" "log_$sig" || fail "SIG$sig: no final line: $(tail -3 "log_$sig")"
    expect_outputs "out_$sig"
    grep -q '"interrupted": true' "out_$sig/report.json" || fail "SIG$sig: report.json does not say interrupted"
  done
  ;;
pool_full)  # 14.6: a full block pool writes every output for the frames done and names a flag that exists
  run_small --synthetic-frames 20 --capacity-blocks 3000 --out out > log 2>&1 && fail "a 3000-block pool sufficed"
  grep -q "outputs written for [1-9][0-9]* of 20 frames" log || fail "no frame count: $(tail -2 log)"
  grep -q -- "--capacity-blocks" log || fail "no flag named: $(tail -2 log)"
  for f in trajectory.txt mesh.ply report.json report.md; do [ -f out/$f ] || fail "missing out/$f"; done
  grep -q '"stopped_by": "frame' out/report.json || fail "report.json does not say why it stopped"
  mem_kib=$(awk '/MemTotal/ {print $2}' /proc/meminfo)
  if [ "${mem_kib:-0}" -lt $((256 * 1024 * 1024)) ]; then  # 2^26 blocks need 256 GiB
    run_small --synthetic-frames 2 --capacity-blocks 67108864 --out big > log 2>&1 && fail "a 256 GiB pool was accepted"
    grep -q "needs 262144 MiB, more than this machine's" log || fail "unclear capacity message: $(cat log)"
    grep -q "^input:" log && fail "the capacity was checked only after opening the input"
  fi
  ;;
untrusted_lists)  # 14.7: a list linked to /dev/zero or a FIFO is refused at once, naming the file and the kind
  "$HF" generate --frames 2 --camera cam.txt --out data > log 2>&1 || fail "generate failed: $(cat log)"
  rm data/groundtruth.txt && ln -s /dev/zero data/groundtruth.txt
  timeout 60 "$HF" run --input data --out out > log 2>&1
  rc=$?
  [ $rc = 1 ] || fail "groundtruth.txt -> /dev/zero: exit $rc: $(tail -2 log)"
  grep -q "groundtruth.txt: cannot read trajectory file: it is a character device" log || fail "$(cat log)"
  rm data/groundtruth.txt && mv data/rgb.txt data/rgb.list && mkfifo data/rgb.txt
  timeout 60 "$HF" run --input data --out out > log 2>&1
  rc=$?
  [ $rc = 1 ] || fail "rgb.txt FIFO: exit $rc (124 = blocked): $(tail -2 log)"
  grep -q "rgb.txt: cannot read image list: it is a FIFO" log || fail "$(cat log)"
  "$HF" eval --gt data --est data/depth.txt > log 2>&1 && fail "eval on a folder succeeded"
  grep -q "it is a folder, not a regular file" log || fail "eval on a folder: $(cat log)"
  ;;
quoting_and_bounds)  # 14.8, 14.9: input quoted short and printable; finite extreme poses are refused, not NaN
  for i in 0 1 2 3 4 5 6 7 8 9; do echo "$i.0 0 0 0 0 0 0 1"; done > zero.txt
  for i in 0 1 2 3 4 5 6 7 8 9; do echo "$i.0 $([ $((i % 2)) = 1 ] && echo 1e308 || echo 0) 0 0 0 0 0 1"; done > ext.txt
  "$HF" eval --gt zero.txt --est ext.txt > log 2>&1 && fail "eval with tx = 1e308 succeeded: $(cat log)"
  grep -q "ext.txt:2: expected coordinates within 1e6 m" log || fail "$(cat log)"
  grep -q -i nan log && fail "NaN printed: $(cat log)"
  { echo "1 0 0 0 0 0 0 1"; printf '2 \033[31m'; head -c 3000 /dev/zero | tr '\0' x; echo " 0 0 0 0 0 1"; } > esc.txt
  "$HF" eval --gt esc.txt --est zero.txt > log 2>&1 && fail "eval on a malformed file succeeded"
  [ "$(wc -c < log)" -lt 200 ] || fail "error line of $(wc -c < log) bytes"
  grep -q $'\033' log && fail "an escape sequence reached the terminal"
  grep -q "esc.txt:2: expected a finite number, got '?\[31mxxx" log || fail "$(cat log)"
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "ok ($CASE)"
