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
  grep -q "Redistribution and use in source and binary forms" "$SRC/LICENSE" || fail "LICENSE is not BSD 3-Clause"
  grep -q "the hashfusion authors" "$SRC/LICENSE" || fail "LICENSE names no copyright holder"
  # every package of the list (build tools aside) is named in THIRD_PARTY.md with its licence
  for p in $(grep -v '^#' "$SRC/scripts/debian-packages.txt"); do
    grep -q -- "$p" "$SRC/THIRD_PARTY.md" || fail "THIRD_PARTY.md does not list $p"
  done
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "ok ($CASE)"
