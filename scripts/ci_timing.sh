#!/usr/bin/env bash
# scripts/ci_timing.sh [COMMIT] [--keep]: the cold CI measurement of issue 32 (bench/results/ci.md).
#
# Clones COMMIT (default HEAD) of this repository into a fresh folder beside it (so ../shared is beside the clone,
# as in CI), then runs what .ci/run runs, scripts/test.sh, with no compiler cache (CCACHE_DISABLE=1) and CI=true,
# timed as a whole, with the phases test.sh reports (release build, release suite beside which the asan build
# runs, asan suite). It prints the phase
# table and, per preset, the 20 most expensive build steps (.ninja_log) and the 20 slowest tests (CTest's cost
# data), and writes them as Markdown to ci_timing.md in the clone's parent folder. Run it on a quiet machine: the
# numbers are wall-clock seconds. The Debian packages must already be installed (scripts/setup.sh; apt is not
# part of the measurement). The clone is removed at the end unless --keep is given.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
commit="HEAD"
keep=0
for arg in "$@"; do
  case "$arg" in
    --keep) keep=1 ;;
    *) commit="$arg" ;;
  esac
done
sha="$(git -C "$repo" rev-parse --short "$commit")"
clone="$(dirname "$repo")/ci_timing_$sha"
report="$(dirname "$repo")/ci_timing_$sha.md"
rm -rf "$clone"
git clone -q --no-hardlinks "$repo" "$clone"
git -C "$clone" checkout -q "$sha"
bash "$clone/scripts/setup.sh" >/dev/null

export CCACHE_DISABLE=1 CI=true
cd "$clone"
phase_names=()
phase_seconds=()
status=0
phase() {  # phase NAME COMMAND...: runs and times one phase; a failure ends the measurement
  local name="$1"
  shift
  local start=$SECONDS
  if ! "$@" >"$clone/ci_timing_$name.log" 2>&1; then
    echo "ci_timing: phase $name failed (log: $clone/ci_timing_$name.log)" >&2
    status=1
    phase_names+=("$name (failed)")
    phase_seconds+=($((SECONDS - start)))
    return 1
  fi
  phase_names+=("$name")
  phase_seconds+=($((SECONDS - start)))
  echo "ci_timing: $name $((SECONDS - start)) s"
}
total_start=$SECONDS
# Exactly what .ci/run runs (scripts/test.sh: the asan build beside the release suite), timed as a whole; its own
# "test.sh: PHASE N s" lines give the phases. The JUnit files keep every test's output (the console shows only
# failures'), for the GoogleTest case counts. A failure is reported and its time is still the number.
# CTest keeps only the first 1024 bytes of a passed test's output unless told otherwise: a suite's case lines
# beyond them would go uncounted.
export HF_CTEST_ARGS_RELEASE="--output-junit $clone/ci_timing_suite_release.xml --test-output-size-passed 16777216"
export HF_CTEST_ARGS_ASAN="--output-junit $clone/ci_timing_suite_asan.xml --test-output-size-passed 16777216"
phase "test.sh" bash scripts/test.sh || true
while read -r line; do
  phase_names+=("${line% *}")
  phase_seconds+=("${line##* }")
done < <(sed -n 's/^test\.sh: \(.*\) \([0-9][0-9]*\) s$/\1 \2/p' "$clone/ci_timing_test.sh.log")
total=$((SECONDS - total_start))

{
  echo "# Cold CI measurement at $sha ($(date -u +%Y-%m-%d), $(nproc) cores, CCACHE_DISABLE=1, CI=true)"
  echo
  echo "| phase | seconds |"
  echo "|---|---|"
  for i in "${!phase_names[@]}"; do
    echo "| ${phase_names[$i]} | ${phase_seconds[$i]} |"
  done
  echo "| **total** | **$total** ($((total / 60)) min $((total % 60)) s) |"
  for preset in release asan; do
    dir="$clone/build/$preset"
    [[ -f "$dir/.ninja_log" ]] || continue
    steps=$(awk 'NR > 1' "$dir/.ninja_log" | wc -l)
    cpu=$(awk 'NR > 1 {s += $2 - $1} END {printf "%.0f", s / 1000}' "$dir/.ninja_log")
    echo
    echo "## $preset: $steps build steps, $cpu s of compiler and linker time; the 20 most expensive"
    echo
    echo "| seconds | step |"
    echo "|---|---|"
    awk 'NR > 1 {printf "%.1f %s\n", ($2 - $1) / 1000, $4}' "$dir/.ninja_log" | sort -rn | sed -n '1,20p' |
      awk '{printf "| %s | `%s` |\n", $1, $2}'
    cost="$dir/Testing/Temporary/CTestCostData.txt"
    log="$clone/ci_timing_suite_$preset.log"  # this preset's part of test.sh's log
    if [[ "$preset" == release ]]; then
      sed -n '/^test\.sh: release build/,/^test\.sh: release suite/p' "$clone/ci_timing_test.sh.log" >"$log"
    else
      sed -n '/^test\.sh: asan build/,$p' "$clone/ci_timing_test.sh.log" >"$log"
    fi
    if [[ -s "$log" ]]; then
      summary=$(grep -E "tests passed|tests failed" "$log" | tail -1 || true)
      skipped=$(grep -cE '\((Skipped|Not Run)\)$' "$log" || true)
      echo
      echo "$preset suite: $summary; $skipped reported skipped (Not Run / SKIP_RETURN_CODE / GTEST_SKIP)"
    fi
    output="$clone/ci_timing_suite_${preset}.xml"
    if [[ -f "$output" ]]; then
      # CTest runs a GoogleTest suite per process; its cases are counted from GoogleTest's own result lines.
      passed=$(grep -cE '\[       OK \] [^ ]+\.[^ ]+ \(' "$output" || true)
      gskipped=$(grep -cE '\[  SKIPPED \] [^ ]+\.[^ ]+ \(' "$output" || true)
      gfailed=$(grep -cE '\[  FAILED  \] [^ ]+\.[^ ]+ \(' "$output" || true)
      echo
      echo "$preset GoogleTest cases: $passed passed, $gskipped skipped, $gfailed failed"
    fi
    if [[ -f "$cost" ]]; then
      echo
      echo "| seconds | test ($preset, 20 slowest) |"
      echo "|---|---|"
      awk '/^---/ {exit} NF == 3 {printf "%.1f %s\n", $3, $1}' "$cost" | sort -rn | sed -n '1,20p' |
        awk '{printf "| %s | %s |\n", $1, $2}'
    fi
  done
} >"$report"
cat "$report"
cd "$repo"
if ((keep == 0)); then
  rm -rf "$clone"
fi
exit $status
