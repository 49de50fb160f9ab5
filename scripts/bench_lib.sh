# Sourced by the scripts/bench_*.sh that run the Release `hashfusion run` over a list of inputs and modes.
#   source scripts/bench_lib.sh
#   bench_init NAME OUT_DIR   # sets $hf (HF_BIN, else build/release/apps/hashfusion: pass a copy so a rebuild
#                             # mid-run changes nothing), $shared (../shared/data), $out, $work (a temp dir removed
#                             # at exit); exits with one line when the binary or ../shared is missing
#   bench_run RUN INPUT [ARGS...]   # hashfusion run --input INPUT --out $out/runs/RUN ARGS, its log beside it;
#                                   # a failed run is reported and the script goes on (its row is then absent)
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
