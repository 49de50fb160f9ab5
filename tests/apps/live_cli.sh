#!/usr/bin/env bash
# Issue 18 end to end: live inputs, `devices`, `record` and the headless viewer through the hashfusion executable,
# without any device: OpenNI2's own Dummy driver (openni2://Dummy, 320x240 at 30 Hz) stands in for a sensor.
#   bash live_cli.sh HASHFUSION SCRATCH_DIR CASE      (exit 77 = skipped, with the reason on stderr)
set -u
# Under the ASan preset LeakSanitizer lists the suppressions it used on stderr; the one-line checks count ours only.
export LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}print_suppressions=0"
HF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
CASE=$3
ROOT=$2/live_cli_$CASE
rm -rf "$ROOT" && mkdir -p "$ROOT" && cd "$ROOT" || exit 1
fail() { echo "FAIL ($CASE): $*" >&2; exit 1; }
skip() { echo "SKIP ($CASE): $*" >&2; exit 77; }
json() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
one_line_error() {  # command, expected text: exit 1, one line on stderr naming it, within 30 s
  local want=$1; shift
  timeout 30 "$HF" "$@" > out.txt 2> err.txt
  local rc=$?
  [ $rc = 1 ] || fail "'$*' exited $rc, expected 1: $(cat err.txt)"
  grep -q -- "$want" err.txt || fail "'$*' did not say '$want': $(cat err.txt)"
  [ "$(grep -c . err.txt)" = 1 ] || fail "'$*' printed more than one line: $(cat err.txt)"
}

case "$CASE" in
devices)
  timeout 30 "$HF" devices > out.txt 2> err.txt || fail "devices failed: $(cat err.txt)"
  for b in openni2 v4l2 libcamera; do grep -q "^$b:" out.txt || fail "no line for $b: $(cat out.txt)"; done
  ;;
bad_inputs)
  one_line_error "openni2://no-such: cannot open" run --input openni2://no-such --out o
  one_line_error "v4l2:///dev/video-none: no such node" run --input v4l2:///dev/video-none --out o
  one_line_error "libcamera://none" run --input libcamera://none --out o
  one_line_error "no such recording" run --input missing.oni --out o
  one_line_error "no depth mode at 640x480" run --input openni2://Dummy --out o
  one_line_error "expected WIDTHxHEIGHT@FPS" record --input openni2://Dummy --live-mode 640 --out r
  one_line_error "not a live input" record --input synthetic:room --out r
  mkdir exists
  one_line_error "already exists" record --input openni2://Dummy --live-mode 320x240@30 --frames 2 --out exists
  ;;
record_replay)
  timeout 60 "$HF" record --input openni2://Dummy --live-mode 320x240@30 --frames 12 --out rec > log 2>&1 ||
    fail "record failed: $(cat log)"
  [ "$(grep -vc '^#' rec/rgb.txt)" = 12 ] || fail "rgb.txt does not list 12 frames"
  [ "$(ls rec/depth | wc -l)" = 12 ] || fail "not 12 depth images"
  timeout 120 "$HF" run --input rec --out run > log 2>&1 || fail "run on the recording failed: $(cat log)"
  [ "$(json run/report.json "j['frames']")" = 12 ] || fail "the replay did not process the 12 recorded frames"
  json run/report.json "j['camera_origin']" | grep -q "camera.json" || fail "the replay did not use the recorded camera"
  [ "$(json run/report.json "[j['camera'][k] for k in ('fx', 'fy', 'cx', 'cy', 'width', 'height')]")" = \
    "[262.5, 262.5, 159.5, 119.5, 320, 240]" ] ||
    fail "camera changed: $(json run/report.json "j['camera']")"
  ;;
live_run_interrupt)
  # SIGINT only once frames flow: a fixed delay raced the start-up under ASan on a loaded machine (CI's one failure,
  # stop 44: the signal came before the first frame, so rightly nothing was written). "registration:" is printed
  # once the device is open; two seconds later the 30 Hz Dummy has delivered frames at any sanitizer's speed.
  "$HF" run --input openni2://Dummy --live-mode 320x240@30 --out run > log 2>&1 &
  pid=$!
  for _ in $(seq 120); do grep -q "^registration:" log && break; kill -0 $pid 2> /dev/null || break; sleep 0.5; done
  grep -q "^registration:" log || { kill -KILL $pid 2> /dev/null; fail "no start within 60 s: $(tail -3 log)"; }
  sleep 2
  kill -INT $pid
  for _ in $(seq 120); do kill -0 $pid 2> /dev/null || break; sleep 0.5; done
  kill -0 $pid 2> /dev/null && { kill -KILL $pid; fail "still running 60 s after SIGINT"; }
  wait $pid
  rc=$?
  [ $rc = 130 ] || fail "exit $rc after SIGINT, expected 130: $(tail -3 log)"
  [ "$(json run/report.json "j['interrupted']")" = True ] || fail "report does not say interrupted"
  [ "$(json run/report.json "j['capture']['frames_captured'] >= j['capture']['frames_processed'] > 0")" = True ] ||
    fail "no capture counters: $(json run/report.json "j['capture']")"
  grep -q "| capture |" run/report.md || fail "report.md has no capture line"
  ;;
screenshot)
  command -v xvfb-run > /dev/null || skip "no xvfb-run for a headless display"
  "$HF" view --help > /dev/null 2>&1 || skip "hashfusion has no view command"
  printf 'fx 131.25\nfy 131.25\ncx 79.5\ncy 59.5\nwidth 160\nheight 120\n' > cam.txt
  timeout 240 xvfb-run -a -s "-screen 0 640x480x24" "$HF" run --input synthetic:room --camera cam.txt \
    --synthetic-frames 8 --out run --screenshot shot.png --screenshot-every 4 > log 2>&1 || {
    grep -q "not built in" log && skip "viewer not built in"
    fail "run --screenshot failed: $(tail -3 log)"
  }
  for f in shot.png shot_000000.png shot_000004.png run/render.png; do [ -s $f ] || fail "missing $f"; done
  timeout 60 xvfb-run -a env HF_VIEWER_NO_EGL=1 "$HF" view run --screenshot view.png > log 2>&1 ||
    fail "view --screenshot failed: $(cat log)"
  [ -s view.png ] || fail "view wrote no screenshot"
  # A bare OBJ mesh (a head from head-features, a model's OBJ) as well: one quad, framed by the view.
  printf 'v 0 0 1\nv 0.5 0 1\nv 0.5 0.5 1\nv 0 0.5 1\nf 1 2 3\nf 1 3 4\n' > quad.obj
  timeout 60 xvfb-run -a env HF_VIEWER_NO_EGL=1 "$HF" view quad.obj --screenshot quad.png > log 2>&1 ||
    fail "view of an OBJ mesh failed: $(cat log)"
  [ -s quad.png ] || fail "view of an OBJ mesh wrote no screenshot"
  # Without any display: EGL's surfaceless platform renders where the build has it (viewer/gl_context.h); without
  # EGL (HF_VIEWER_NO_EGL=1 stands in for a build without it) one clear line and a non-zero exit.
  if env -u DISPLAY "$HF" view run --screenshot egl.png > log 2>&1; then
    [ -s egl.png ] || fail "view without a display wrote no screenshot"
    cmp -s egl.png view.png || fail "the EGL screenshot differs from the GLFW one under Xvfb"
  else
    grep -q "no display" log || fail "no clear message without a display: $(cat log)"
  fi
  env -u DISPLAY HF_VIEWER_NO_EGL=1 "$HF" view run --screenshot nodisplay.png > log 2>&1 &&
    fail "view without a display or EGL succeeded"
  grep -q "no display" log || fail "no clear message without a display: $(cat log)"
  ;;
*) fail "unknown case" ;;
esac
exit 0
