#!/usr/bin/env bash
# Second README command: set up, build and run the whole test suite twice: Release (gcc), then clang with
# AddressSanitizer + UndefinedBehaviorSanitizer and libFuzzer runs of every parser. Fails on any failure or report.
#
# The sanitizer build runs beside the release suite at the lowest priority (nice 19): the suite's tests leave a
# core idle part of the time (waiting on child processes, a scheduler, a replay's clock), which the build takes,
# while a test that wants the core gets it (bench/results/ci.md, issue 32). HF_CTEST_ARGS_RELEASE /
# HF_CTEST_ARGS_ASAN add arguments to each ctest (scripts/ci_timing.sh: --output-junit).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
took() { echo "test.sh: $1 $((SECONDS - $2)) s"; }
start=$SECONDS
bash scripts/build.sh release
took "release build" "$start"
mkdir -p build
asan_start=$SECONDS
nice -n 19 bash scripts/build.sh asan >build/asan_build.log 2>&1 &
asan_build=$!
start=$SECONDS
release_status=0
# shellcheck disable=SC2086 # word splitting of the optional arguments is intended
ctest --preset release ${HF_CTEST_ARGS_RELEASE:-} || release_status=$?
took "release suite" "$start"
if ! wait "$asan_build"; then
  tail -n 40 build/asan_build.log
  echo "test.sh: the asan build failed (build/asan_build.log)" >&2
  exit 1
fi
took "asan build (from its start beside the release suite)" "$asan_start"
if ((release_status != 0)); then
  echo "test.sh: the release suite failed" >&2
  exit "$release_status"
fi
start=$SECONDS
# shellcheck disable=SC2086
ctest --preset asan ${HF_CTEST_ARGS_ASAN:-}
took "asan+ubsan suite" "$start"
