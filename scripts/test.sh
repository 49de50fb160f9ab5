#!/usr/bin/env bash
# Second README command: set up, build and run the whole test suite twice: Release (gcc), then clang with
# AddressSanitizer + UndefinedBehaviorSanitizer and libFuzzer runs of every parser. Fails on any failure or report.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
start=$SECONDS
bash scripts/build.sh release
ctest --preset release
echo "release suite: $((SECONDS - start)) s"
start=$SECONDS
bash scripts/build.sh asan
ctest --preset asan
echo "asan+ubsan suite: $((SECONDS - start)) s"
