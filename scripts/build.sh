#!/usr/bin/env bash
# scripts/build.sh PRESET [TARGET...]: configure (once) and build one CMake preset (release | asan): the given
# targets only (the demo builds what it runs), or every target when none is given (the test suite).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
preset="${1:-release}"
shift || true
if [[ ! -f "build/$preset/build.ninja" ]]; then
  cmake --preset "$preset" >/dev/null
fi
if (($# > 0)); then
  cmake --build --preset "$preset" --target "$@"
else
  cmake --build --preset "$preset"
fi
