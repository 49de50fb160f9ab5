#!/usr/bin/env bash
# First README command: set up, build in Release, run the main job on the embedded default (a synthetic room
# sequence generated on the fly) and print where the outputs are.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
# What the demo offers and what `cmake --install build/release` copies: the CLI, the Python module and the exported
# libraries (hf_installable; the test command builds the tests and benchmarks into the same folder).
bash scripts/build.sh release hf_installable
out="${HF_DEMO_OUT:-$PWD/out/demo}"
./build/release/apps/hashfusion run --input synthetic:room --out "$out" "$@"
echo "python: PYTHONPATH=$PWD/build/release/python python3 -c 'import hashfusion as hf'  (README.md, Python)"
