#!/usr/bin/env bash
# Issue 36 end to end: what a user coming from Open3D / PCL / InfiniTAM expects of the CLI and the repository.
#   bash issue36.sh HASHFUSION SCRATCH_DIR CASE
# One CASE per behaviour (CTest runs each as its own test); each prints why it failed and exits 1. Every command
# that could hang runs under `timeout`.
set -u
HF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SRC=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
ROOT=$2/issue36_$3
CASE=$3
rm -rf "$ROOT" && mkdir -p "$ROOT" && cd "$ROOT" && ROOT=$(pwd) || exit 1
fail() { echo "FAIL ($CASE): $*" >&2; exit 1; }
printf 'fx 131.25\nfy 131.25\ncx 79.5\ncy 59.5\nwidth 160\nheight 120\n' > cam.txt

case "$CASE" in
readme)  # the README opens with its title and summary, then exactly the two commands; .ci/run runs the second
  [ "$(head -1 "$SRC/README.md")" = "# hashfusion" ] || fail "README.md does not open with its title"
  block=$(awk '/^```sh$/{n++; next} n==1 && /^```$/{exit} n==1{print}' "$SRC/README.md")
  [ "$(printf '%s\n' "$block" | wc -l)" = 2 ] || fail "the first sh block holds more than two commands: $block"
  [ "$(printf '%s\n' "$block" | sed -n 1p)" = "bash scripts/demo.sh" ] || fail "first command: $block"
  second=$(printf '%s\n' "$block" | sed -n 2p)
  grep -qxF "$second" "$SRC/.ci/run" || fail ".ci/run does not run the README's second command '$second'"
  first_block_line=$(grep -n '^```' "$SRC/README.md" | head -1 | cut -d: -f1)
  summary_line=$(grep -n '^hashfusion is ' "$SRC/README.md" | head -1 | cut -d: -f1)
  [ -n "$summary_line" ] && [ "$summary_line" -lt "$first_block_line" ] || fail "no summary before the commands"
  # status table: one short line per part, each under 160 characters
  awk '/^## Status/{s=1; next} s && /^## /{exit} s && /^\|/ && length($0) > 160 {print; bad=1} END{exit bad}' \
    "$SRC/README.md" || fail "a status row longer than 160 characters"
  # the synopsis and run --help name every registration method the registry knows
  known=$("$HF" config --registration no-such 2>&1 | sed -n 's/.*(known: \(.*\))$/\1/p' | tr -d ,)
  [ -n "$known" ] || fail "no list of registration methods"
  synopsis=$(grep -m1 -- '--registration combined|' "$SRC/README.md")
  "$HF" run --help > help.txt
  for m in $known; do
    printf '%s\n' "$synopsis" | grep -q -- "[[| ]$m[]|]" || fail "the README's synopsis lacks $m: $synopsis"
    grep -A3 -- "--registration" help.txt | grep -q -- "[ :]$m[,]\?" || fail "run --help lacks $m"
  done
  grep -q "Redistribution and use in source and binary forms" "$SRC/LICENSE" || fail "LICENSE is not BSD 3-Clause"
  grep -q "the hashfusion authors" "$SRC/LICENSE" || fail "LICENSE names no copyright holder"
  # every package of the list (build tools aside) is named in THIRD_PARTY.md with its licence
  for p in $(grep -v '^#' "$SRC/scripts/debian-packages.txt"); do
    grep -q -- "$p" "$SRC/THIRD_PARTY.md" || fail "THIRD_PARTY.md does not list $p"
  done
  ;;
cli_errors)  # every argument error: exit 1 and one short line (not CLI11's 104-109, never DBL_MAX's 309 digits)
  check_error() {  # ARGS...: exit 1, one line, under 200 characters, naming the option
    timeout 60 "$HF" "$@" > out.txt 2> log
    rc=$?
    [ $rc = 1 ] || fail "hashfusion $*: exit $rc, expected 1: $(head -c 300 log)"
    [ "$(wc -l < log)" = 1 ] || fail "hashfusion $*: expected one line, got: $(cat log)"
    [ "$(wc -c < log)" -lt 200 ] || fail "hashfusion $*: a long line: $(cat log)"
  }
  check_error
  check_error no-such-command
  check_error run --voxel-m 1e9 --out o
  grep -q -- "--voxel-m: expected 0.0001..10 m, got 1e+09" log || fail "voxel range: $(cat log)"
  check_error run --voxel-m abc --out o
  check_error run --max-frames -1 --out o
  check_error run --tracking-level 7 --out o
  check_error run --no-such-flag
  check_error run --screenshot-every 0 --out o
  check_error bench --peer-voxel-m=-1e308 --input synthetic:room --out o
  grep -q "expected a finite number > 0, got -1e+308" log || fail "peer voxel: $(cat log)"
  check_error bench --voxel-m 20 --input synthetic:room --out o  # the same range as run's
  grep -q -- "--voxel-m: expected 0.0001..10 m, got 20" log || fail "bench voxel range: $(cat log)"
  check_error run --backend cuda --out o  # refused with the configuration, before the input is opened
  grep -q "unknown reduction backend 'cuda' (known: cpu, opencl)" log || fail "backend: $(cat log)"
  check_error record --frames 0 --out o
  check_error eval --est x.txt
  check_error eval --gt a --est b --delta-s 0
  check_error model --acceptance 2 --out o
  check_error head-features --out o
  grep -q "head-features: --input MESH is required" log || fail "$(cat log)"
  # a seed is unsigned (CLI11 alone wraps -1 to 2^64 - 1); synthetic frame counts share one range
  for sub in run generate bench; do
    check_error $sub --seed=-1 --input synthetic:room --out o
    grep -q -- "--seed: expected 0..1.84467e+19, got -1" log || fail "$sub seed: $(cat log)"
  done
  check_error generate --frames 200000 --out o
  grep -q -- "--frames: expected 1..100000 frames, got 200000" log || fail "generate frames: $(cat log)"
  check_error run --synthetic-frames 200000 --out o
  grep -q -- "--synthetic-frames: expected 1..100000 frames, got 200000" log || fail "run frames: $(cat log)"
  # lidar: ranges checked before any point is read (1e308 failed deep in the clustering operator)
  check_error lidar --input synthetic:1 --cell-m=-1e308 --out o
  check_error lidar --input synthetic:1 --t-m-per-m 1e308 --out o
  grep -q -- "--t-m-per-m: expected 0..1000 m per m, got 1e+308" log || fail "lidar t: $(cat log)"
  check_error lidar --input synthetic:1 --sweep-t-m-per-m 1,1e308 --out o
  grep -q -- "--sweep-t-m-per-m: expected 0..1000 m per m, got 1e+308" log || fail "lidar sweep: $(cat log)"
  check_error lidar --input synthetic:-3 --out o
  grep -q -- "synthetic:SEED: expected a whole number" log || fail "lidar seed: $(cat log)"
  [ ! -e o ] || fail "an argument error created o"
  # every subcommand that writes files takes --out, by default out/SUBCOMMAND; CLI11 prints it as
  # "  --out TEXT=out/run  output folder" (the description on the next line when the default is long)
  for sub in eval lidar generate head-features model; do  # a hidden deprecated alias leaves no "Excludes: " behind
    "$HF" $sub --help > help.txt 2>&1 || fail "$sub --help: exit $?"
    ! grep -Eq "Excludes: ?([^-]|$)" help.txt || fail "$sub --help: $(grep -E "Excludes: ?([^-]|$)" help.txt)"
  done
  for sub in run generate bench lidar head-features model record; do
    "$HF" $sub --help > help.txt 2>&1 || fail "$sub --help: exit $?"
    grep -Eq -- "^ +--out TEXT=out/$sub( |$)" help.txt || fail "$sub --help: $(grep -- --out help.txt)"
  done
  # and writes there when --out is not given (generate: the quickest of them)
  timeout 120 "$HF" generate --frames 1 --camera cam.txt > log 2>&1 || fail "generate without --out: $(cat log)"
  [ -s out/generate/groundtruth.txt ] || fail "generate without --out wrote no out/generate: $(cat log)"
  check_error generate --frames 1 --camera cam.txt  # a second time: names --force
  grep -q "out/generate: already exists (choose another --out, or --force to replace" log || fail "$(cat log)"
  timeout 120 "$HF" generate --frames 1 --camera cam.txt --force > log 2>&1 || fail "generate --force: $(cat log)"
  ;;
version)  # hashfusion --version: the version and the commit built from
  "$HF" --version > log 2>&1 || fail "exit $?: $(cat log)"
  grep -Eq "^hashfusion [0-9]+\.[0-9]+\.[0-9]+ \(commit ([0-9a-f]{40}(-dirty)?|unknown)\)$" log || fail "$(cat log)"
  ;;
report)  # report.json: provenance, a structured camera, floats shortest; --config takes a whole report.json
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 3 --out a > log 2>&1 ||
    fail "run: $(tail -3 log)"
  python3 - a/report.json "$("$HF" --version)" "$SRC/docs/report.md" <<'PY' || fail "report.json"
import json, re, sys
j = json.load(open(sys.argv[1]))
version = sys.argv[2].split()[1]
assert j["version"] == version, j["version"]
assert re.fullmatch(r"[0-9a-f]{40}(-dirty)?|unknown", j["commit"]), j["commit"]
assert sys.argv[2].endswith("(commit %s)" % j["commit"])
assert j["command_line"] == "hashfusion run --input synthetic:room --camera cam.txt --synthetic-frames 3 --out a", \
    j["command_line"]
assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", j["started_utc"]), j["started_utc"]
assert j["camera"] == {"fx": 131.25, "fy": 131.25, "cx": 79.5, "cy": 59.5, "width": 160, "height": 120}, j["camera"]
# floats of float fields as typed: 0.1, not 0.10000000149011612
ro = j["config"]["registration_options"]
assert ro["max_dist_m"] == 0.1 and ro["rgb_weight"] == 0.4, ro
text = json.dumps(j["config"])  # each number as Python reads it back, shortest form
assert "0000000" not in text and "9999999" not in text, text
# docs/report.md names every field (and every field of the per-frame rows and the colour check)
doc = open(sys.argv[3]).read()
fields = list(j) + list(j["per_frame"][0]) + list(j["colour_check"])
missing = [k for k in fields if "`%s`" % k not in doc]
assert not missing, "docs/report.md does not list %s" % missing
PY
  # the whole report.json as --config repeats the run's configuration
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 3 --config a/report.json \
    --out b > log 2>&1 || fail "run --config report.json: $(tail -3 log)"
  python3 -c "import json,sys; a, b = (json.load(open(p))['config'] for p in sys.argv[1:]); assert a == b" \
    a/report.json b/report.json || fail "--config report.json gave another configuration"
  cmp a/trajectory.txt b/trajectory.txt || fail "--config report.json: another trajectory"
  ;;
aliases)  # the old spellings still run, with a one-line deprecation notice naming the new one
  printf '1 0 0 0 0 0 0 1\n2 0.1 0 0 0 0 0 1\n3 0.2 0 0 0 0 0 1\n4 0.3 0 0 0 0 0 1\n' > t.txt
  "$HF" eval --gt t.txt --est t.txt --max-difference 0.02 --offset 0 --delta 1 --json > new.json 2> log ||
    fail "eval with the old spellings: $(cat log)"
  grep -qx "hashfusion: --max-difference is deprecated; use --max-difference-s" log || fail "$(cat log)"
  grep -qx "hashfusion: --delta is deprecated; use --delta-s" log || fail "$(cat log)"
  "$HF" eval --gt t.txt --est t.txt --max-difference-s 0.02 --offset-s 0 --delta-s 1 --json > now.json 2> log2 ||
    fail "eval: $(cat log2)"
  [ ! -s log2 ] || fail "the new spellings printed: $(cat log2)"
  cmp new.json now.json || fail "the aliases gave another result"
  timeout 60 "$HF" eval --gt t.txt --est t.txt --max-difference 0.02 --max-difference-s 0.02 > /dev/null 2> log
  [ $? = 1 ] || fail "an option and its alias together were accepted"
  # lidar's: the same outputs (the input's path aside, which names the folder)
  timeout 120 "$HF" lidar --input synthetic:1 --t 2 --areas 50000,1000000,5000000 --sweep-t 1,2 --out lo > /dev/null \
    2> log || fail "lidar with the old spellings: $(cat log)"
  for o in t areas sweep-t; do
    grep -q "^hashfusion: --$o is deprecated; use --$o-m" log || fail "no notice for --$o: $(cat log)"
  done
  timeout 120 "$HF" lidar --input synthetic:1 --t-m-per-m 2 --areas-m2 50000,1000000,5000000 --sweep-t-m-per-m 1,2 \
    --out ln > /dev/null 2> log || fail "lidar: $(cat log)"
  for f in classes.tif buildings.png classes.png synthetic.las; do cmp lo/$f ln/$f || fail "lidar aliases: $f differs"; done
  sed 's#lo/synthetic.las#ln/synthetic.las#' lo/report.json | cmp - ln/report.json || fail "lidar aliases: report.json"
  ;;
maps)  # run --save-map / --save-cloud / --load-map: written with the outputs (also on SIGTERM), read back
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 4 --voxel-m 0.02 --save-map \
    --save-cloud --out a > log 2>&1 || fail "run --save-map: $(tail -3 log)"
  [ -s a/map.hfmap ] && [ "$(head -c 8 a/map.hfmap)" = HFVOLUME ] || fail "no map.hfmap in --out"
  grep -q '"map.hfmap"' a/report.json && grep -q '"cloud.ply"' a/report.json || fail "outputs do not list them"
  head -c 400 a/cloud.ply | grep -q "property float nx" || fail "cloud.ply without normals"
  head -c 400 a/cloud.ply | grep -q "property uchar red" || fail "cloud.ply without colour"
  ! head -c 400 a/cloud.ply | grep -q "element face" || fail "cloud.ply has faces"
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 4 --voxel-m 0.02 \
    --save-cloud "$ROOT/c.pcd" --save-map "$ROOT/m.hfmap" --out b > log 2>&1 || fail "run --save-cloud: $(tail -3 log)"
  head -c 300 c.pcd | grep -q "^FIELDS x y z" || fail "c.pcd: $(head -c 200 c.pcd)"
  head -c 300 c.pcd | grep -q "normal_x" && head -c 300 c.pcd | grep -q "rgb" || fail "c.pcd fields: $(head -5 c.pcd)"
  cmp m.hfmap a/map.hfmap || fail "the same run saved another map"
  # a path into --out itself is the bare name: written inside the transaction, listed with the outputs
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 4 --voxel-m 0.02 \
    --save-map g/./map.hfmap --out g > log 2>&1 || fail "run --save-map g/./map.hfmap: $(tail -3 log)"
  cmp g/map.hfmap a/map.hfmap && grep -q '"map.hfmap"' g/report.json || fail "--save-map OUT/map.hfmap"
  # Open3D, where installed, reads both with colour and unit normals, the same points
  if /usr/bin/python3 -c "import open3d" 2> /dev/null; then
    /usr/bin/python3 - a/cloud.ply c.pcd <<'PY' || fail "Open3D read the clouds differently"
import sys
import numpy as np
import open3d as o3d
ply, pcd = (o3d.io.read_point_cloud(p) for p in sys.argv[1:])
for c in (ply, pcd):
    assert len(c.points) > 1000 and c.has_colors() and c.has_normals(), c
    assert np.allclose(np.linalg.norm(np.asarray(c.normals), axis=1), 1, atol=1e-5)
assert np.array_equal(np.asarray(ply.points), np.asarray(pcd.points))
assert np.abs(np.asarray(ply.colors) - np.asarray(pcd.colors)).max() <= 1 / 255 + 1e-9
PY
  else
    echo "skipped: the Open3D round trip (python3-open3d not installed)"
  fi
  [ ! -e b/m.hfmap ] || fail "a path was put into --out"
  # continuing in the map: the synthetic frames start at their ground truth, so the run tracks from the first frame
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 4 --voxel-m 0.02 \
    --load-map a/map.hfmap --out c > log 2>&1 || fail "run --load-map: $(tail -3 log)"
  grep -q "^map: continuing in a/map.hfmap" log || fail "$(cat log)"
  python3 -c "import json,sys; j=json.load(open('c/report.json')); assert j['frames_lost'] == 0 and j['ate_rmse_m'] < 0.01, j['ate_rmse_m']" ||
    fail "the continued run lost frames or drifted"
  timeout 60 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 2 --load-map a/map.hfmap --out d \
    > log 2>&1
  [ $? = 1 ] || fail "a map of 2 cm voxels loaded into a 1 cm configuration"
  grep -q "a/map.hfmap: load_map: the map has voxels of 0.02 m" log || fail "$(cat log)"
  [ "$(grep -c "^hashfusion:" log)" = 1 ] || fail "expected one error line: $(cat log)"  # besides input: / camera:
  # a FILE outside --out that cannot be written fails before the first frame (it is written last), in one line
  timeout 60 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 20 --save-map "$ROOT/none/m.hfmap" \
    --out f > log 2>&1
  [ $? = 1 ] && [ "$(wc -l < log)" = 1 ] || fail "a map into a missing folder: $(cat log)"
  grep -qx "hashfusion: --save-map: $ROOT/none/m.hfmap: no folder $ROOT/none" log || fail "$(cat log)"
  timeout 60 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 20 --save-cloud "$ROOT/c.xyz" \
    --out f > log 2>&1
  [ $? = 1 ] && [ "$(wc -l < log)" = 1 ] || fail "a cloud of another type: $(cat log)"
  grep -q -- "--save-cloud: $ROOT/c.xyz: expected a file name ending in .ply or .pcd" log || fail "$(cat log)"
  [ ! -e f ] || fail "a refused --save-map / --save-cloud left f"
  printf 'not a map' > bad.hfmap
  timeout 60 "$HF" run --input synthetic:room --camera cam.txt --load-map bad.hfmap --out d > log 2>&1
  [ $? = 1 ] && grep -q "bad.hfmap" log || fail "a bad map: $(cat log)"
  # SIGTERM: the map is written with the other outputs
  "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 100000 --voxel-m 0.02 --save-map --out e \
    > log 2>&1 &
  pid=$!
  trap 'kill $pid 2>/dev/null' EXIT
  for _ in $(seq 600); do grep -q "^registration:" log && break; sleep 0.1; done
  sleep 2
  kill -s TERM $pid
  wait $pid
  rc=$?
  [ $rc = 143 ] || fail "exit $rc after SIGTERM: $(tail -3 log)"
  [ -s e/map.hfmap ] && grep -q '"map.hfmap"' e/report.json || fail "no map after SIGTERM"
  ;;
config_doc)  # hashfusion config: every key with unit, default, range, meaning; docs/config.md is its output
  "$HF" config --markdown > config.md 2> log || fail "config --markdown: $(cat log)"
  diff -u "$SRC/docs/config.md" config.md > diff.txt ||
    fail "docs/config.md is stale: cmake --build --preset release --target docs ($(head -20 diff.txt))"
  "$HF" config > table.txt 2> log || fail "config: $(cat log)"
  grep -Eq "^volume.voxel_m +m +0.01 +0.0001..10 m +edge of a voxel$" table.txt || fail "$(grep voxel_m table.txt)"
  ! grep -q "a knob of combined" table.txt || fail "a key of the default method without a row: $(grep knob table.txt)"
  "$HF" config --registration gicp > gicp.txt 2> log || fail "config --registration gicp: $(cat log)"
  ! grep -q "registration_options.rgb_weight" gicp.txt || fail "combined's knobs listed for gicp"
  "$HF" config --defaults > defaults.json || fail "config --defaults"
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 2 --config defaults.json \
    --out a > log 2>&1 || fail "run --config (the defaults): $(tail -2 log)"
  printf '{"volume": {"voxel_m": 50}}' > big.json
  timeout 60 "$HF" run --input synthetic:room --camera cam.txt --config big.json --out b > log 2>&1
  [ $? = 1 ] || fail "voxel_m 50 accepted"
  grep -qx "hashfusion: big.json: volume.voxel_m: expected 0.0001..10 m, got 50" log || fail "$(cat log)"
  timeout 60 "$HF" config --registration no-such > log 2>&1
  [ $? = 1 ] && grep -q "unknown registration method" log || fail "$(cat log)"
  ;;
groundtruth_link)  # issue 35's leftover: a TUM folder whose groundtruth.txt is a link loop or dangles
  "$HF" generate --frames 2 --camera cam.txt --out tum > log 2>&1 || fail "generate: $(cat log)"
  rm tum/groundtruth.txt
  ln -s groundtruth.txt tum/groundtruth.txt  # a loop
  timeout 60 "$HF" run --input tum --camera cam.txt --out o > log 2>&1
  rc=$?
  [ $rc = 1 ] || fail "a link loop: exit $rc: $(cat log)"
  grep -q "groundtruth.txt: cannot read the ground truth (Too many levels of symbolic links)" log || fail "$(cat log)"
  rm tum/groundtruth.txt
  ln -s nowhere.txt tum/groundtruth.txt
  timeout 60 "$HF" run --input tum --camera cam.txt --out o > log 2>&1
  [ $? = 1 ] && grep -q "groundtruth.txt: cannot read the ground truth (a link to nothing)" log || fail "$(cat log)"
  rm tum/groundtruth.txt
  timeout 120 "$HF" run --input tum --camera cam.txt --out o > log 2>&1 || fail "no ground truth at all: $(cat log)"
  ;;
pictures)  # coloured render.png; view frames a bare mesh, --camera-pose; the lidar PNGs decode and carry legends
  PNG="python3 $SRC/tests/apps/png_pixels.py"
  timeout 300 "$HF" run --input synthetic:room --camera cam.txt --synthetic-frames 3 --out a > log 2>&1 ||
    fail "run: $(tail -3 log)"
  # render.png in the fused colours: most surface pixels are not grey (the room's walls are coloured)
  python3 - a/render.png <<PY || fail "render.png is grey"
import sys; sys.path.insert(0, "$SRC/tests/apps"); import png_pixels
w, h, rows = png_pixels.read(sys.argv[1])
surface = [p for row in rows for p in row if max(p) > 0]
coloured = [p for p in surface if max(p) - min(p) > 24]
assert len(surface) > w * h // 4, len(surface)
assert len(coloured) > len(surface) // 2, (len(coloured), len(surface))
PY
  # --camera-pose: checked before anything else (no display needed), one line, exit 1
  for bad in "1 2 3" "0 0 abc 0 0 0 1" "0 0 0 0 0 0 0" "0 0 0 0 0 0 nan"; do
    env -u DISPLAY timeout 60 "$HF" view a/mesh.ply --camera-pose "$bad" --screenshot x.png > out.txt 2> log
    rc=$?
    [ $rc = 1 ] || fail "view --camera-pose '$bad': exit $rc: $(cat log)"
    [ "$(wc -l < log)" = 1 ] && grep -q "view: --camera-pose: expected" log || fail "'$bad': $(cat log)"
    [ ! -e x.png ] || fail "a bad pose wrote a screenshot"
  done
  # the sanitizer build has the view subcommand but no viewer in it (it says so, exit 1)
  viewer_built=yes
  env -u DISPLAY timeout 60 "$HF" view a/mesh.ply --screenshot probe.png 2>&1 | grep -q "viewer is not built in" &&
    viewer_built=no
  rm -f probe.png
  if command -v xvfb-run > /dev/null && [ "$viewer_built" = yes ]; then
    # a bare mesh: framed whole (surface pixels, none on the border), in its colours
    timeout 120 xvfb-run -a env HF_VIEWER_NO_EGL=1 "$HF" view a/mesh.ply --camera cam.txt --screenshot bare.png \
      > log 2>&1 || fail "view mesh.ply: $(cat log)"
    python3 - bare.png <<PY || fail "the bare mesh is not framed whole or not coloured"
import sys; sys.path.insert(0, "$SRC/tests/apps"); import png_pixels
w, h, rows = png_pixels.read(sys.argv[1])
surface = [(x, y) for y in range(h) for x in range(w) if max(rows[y][x]) > 0]
border = [(x, y) for x, y in surface if x < 2 or y < 2 or x >= w - 2 or y >= h - 2]
coloured = [1 for x, y in surface if max(rows[y][x]) - min(rows[y][x]) > 24]
assert len(surface) > w * h // 20, len(surface)  # not a speck
assert not border, border[:5]
assert len(coloured) > len(surface) // 2, (len(coloured), len(surface))
PY
    # the first camera's pose (the room's first frame looks at its content from the origin): another picture
    timeout 120 xvfb-run -a env HF_VIEWER_NO_EGL=1 "$HF" view a/mesh.ply --camera cam.txt \
      --camera-pose "$(awk '!/^#/ {print $2, $3, $4, $5, $6, $7, $8; exit}' a/trajectory.txt)" \
      --screenshot posed.png > log 2>&1 || fail "view --camera-pose: $(cat log)"
    [ -s posed.png ] && ! cmp -s posed.png bare.png || fail "--camera-pose made no difference"
  else
    echo "skipped the screenshots: no xvfb-run or no viewer"
  fi
  # lidar: classes.png and buildings.png (libpng, lidar/png_stream.h) decode and end with a legend strip
  timeout 300 "$HF" lidar --input synthetic:1 --out l > log 2>&1 || fail "lidar: $(tail -3 log)"
  for f in classes buildings; do
    python3 - l/$f.png <<PY || fail "l/$f.png: no legend or does not decode"
import sys; sys.path.insert(0, "$SRC/tests/apps"); import png_pixels
w, h, rows = png_pixels.read(sys.argv[1])
strip = rows[h - 24:]  # the legend: white with black swatch borders and names
white = sum(1 for row in strip for p in row if p == (255, 255, 255))
dark = sum(1 for row in strip for p in row if max(p) < 60)
assert white > len(strip) * w // 2 and dark > 50, (white, dark)
PY
  done
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "ok ($CASE)"
