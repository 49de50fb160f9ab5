#!/usr/bin/env bash
# The viewer's model view costs the tracking thread one shaded raycast (viewer/run_viewer.h) per view it shows.
# This runs the same synthetic sequence twice, headless: without the viewer, and with --screenshot-every 1 (a model
# view from the following free camera at the input camera's 640 x 480 on every frame, the window's worst case at its
# 15 Hz cap), and prints the wall time per frame of each and their difference. Usage:
#   bench/viewer_model_view.sh [HASHFUSION] [FRAMES]   (default build/release/apps/hashfusion, 40 frames)
set -euo pipefail
HF=${1:-build/release/apps/hashfusion}
FRAMES=${2:-40}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
per_frame_ms() {
  local start end
  start=$(date +%s.%N)
  "$HF" run --input synthetic:room --synthetic-frames "$FRAMES" --out "$WORK/$1" "${@:2}" > /dev/null 2>&1
  end=$(date +%s.%N)
  echo "($end - $start) * 1000 / $FRAMES" | bc -l
}
plain=$(per_frame_ms plain)
viewed=$(per_frame_ms viewed --screenshot "$WORK/shot.png" --screenshot-every 1)
printf 'without viewer  %.1f ms/frame\nmodel view/frame %.1f ms/frame\ndifference      %.1f ms/frame\n' \
  "$plain" "$viewed" "$(echo "$viewed - $plain" | bc -l)"
