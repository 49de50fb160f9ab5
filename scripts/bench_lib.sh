# Sourced by the scripts/bench_*.sh that run the Release `hashfusion run` over a list of inputs and modes.
#   source scripts/bench_lib.sh
#   bench_init NAME OUT_DIR   # sets $hf (HF_BIN, else build/release/apps/hashfusion: pass a copy so a rebuild
#                             # mid-run changes nothing), $shared (../shared/data), $out, $work (a temp dir removed
#                             # at exit); exits with one line when the binary or ../shared is missing
#   bench_run RUN INPUT [ARGS...]   # hashfusion run --input INPUT --out $out/runs/RUN ARGS, its log beside it;
#                                   # a failed run is reported and the script goes on (its row is then absent)
#   bench_ate_table NAME COLUMN     # $out/NAME.{json,md} from every $out/runs/INPUT__VARIANT/report.json: input,
#                                   # VARIANT under the heading COLUMN, frames, lost, tracked by, ATE cm; printed
bench_init() {
  bench_name="$1"
  out="$2"
  hf="${HF_BIN:-build/release/apps/hashfusion}"
  shared="../shared/data"
  [[ -x "$hf" ]] || { echo "$bench_name: build first ($hf missing)" >&2; exit 1; }
  [[ -d "$shared" ]] || { echo "$bench_name: $shared is absent" >&2; exit 1; }
  mkdir -p "$out/runs"
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
}

bench_run() {
  local run="$1" input="$2"
  shift 2
  echo "$bench_name: $run" >&2
  "$hf" run --input "$input" --out "$out/runs/$run" "$@" > /dev/null 2> "$out/runs/$run.log" ||
    echo "  failed (see $out/runs/$run.log)" >&2
}

# A TUM or 7-Scenes input's run name: its folder's name, synthetic:NAME as synthetic_NAME.
bench_input_name() {
  local name
  name="$(basename "$1")"
  echo "${name/synthetic:/synthetic_}"
}

# bench_fr1_rpy_0_269: fr1/rpy frames 0-269 joined from ../shared's two contiguous excerpts into
# $work/tum_fr1_rpy_frames0_269 (links, lists joined; the first excerpt's groundtruth.txt covers both).
bench_fr1_rpy_0_269() {
  local joined="$work/tum_fr1_rpy_frames0_269" d list
  mkdir -p "$joined/rgb" "$joined/depth"
  for d in tum_fr1_rpy_first150 tum_fr1_rpy_frames150_269; do
    ln -s "$(realpath "$shared/$d")"/rgb/* "$joined/rgb/"
    ln -s "$(realpath "$shared/$d")"/depth/* "$joined/depth/"
  done
  for list in rgb depth; do
    { grep '^#' "$shared/tum_fr1_rpy_first150/$list.txt"
      grep -hv '^#' "$shared/tum_fr1_rpy_first150/$list.txt" "$shared/tum_fr1_rpy_frames150_269/$list.txt"; } \
      > "$joined/$list.txt"
  done
  cp "$shared/tum_fr1_rpy_first150/groundtruth.txt" "$joined/"
}

# bench_seven_scenes_halves: 7-Scenes frames 0-99 and 100-199 as $work/7scenes_frames0_99 and
# $work/7scenes_frames100_199 (links under their own names; the reader takes any frame-NNNNNN run).
bench_seven_scenes_halves() {
  local seven d first last i f
  seven="$(realpath "$shared/7scenes_tsdf_fusion_first200")"
  for first in 0 100; do
    last=$((first + 99))
    d="$work/7scenes_frames${first}_${last}"
    mkdir -p "$d"
    cp "$seven/camera-intrinsics.txt" "$d/"
    for i in $(seq "$first" "$last"); do
      f="$(printf 'frame-%06d' "$i")"
      ln -s -t "$d" "$seven/$f.color.jpg" "$seven/$f.depth.png" "$seven/$f.pose.txt"
    done
  done
}

bench_ate_table() {
  python3 - "$out" "$1" "$2" <<'PY'
import json, os, sys
out, name, column = sys.argv[1:4]
rows = []
for run in sorted(os.listdir(os.path.join(out, "runs"))):
    p = os.path.join(out, "runs", run, "report.json")
    if not os.path.isfile(p):
        continue
    j = json.load(open(p))
    key, variant = run.split("__", 1)
    ate = j.get("ate_rmse_m")
    rows.append({"input": key, column: variant, "frames": j["frames"], "lost": j["frames_lost"],
                 "ate_cm": None if ate is None else 100 * ate,
                 "tracking": j.get("colour_check", {}).get("tracking_registration")})
json.dump(rows, open(os.path.join(out, name + ".json"), "w"), indent=1)
with open(os.path.join(out, name + ".md"), "w") as md:
    md.write(f"| input | {column} | frames | lost | tracked by | ATE cm |\n|---|---|---|---|---|---|\n")
    for r in rows:
        ate = "-" if r["ate_cm"] is None else f"{r['ate_cm']:.3f}"
        md.write(f"| {r['input']} | {r[column]} | {r['frames']} | {r['lost']} | {r['tracking']} | {ate} |\n")
print(open(os.path.join(out, name + ".md")).read())
PY
}
