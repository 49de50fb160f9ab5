#!/usr/bin/env bash
# scripts/bench_ate_levers.sh OUT_DIR INPUTS MODES: issue 34 part 4's levers ("what else moves ATE"), each a config
# of the Release `hashfusion run` (defaults otherwise; loop closure on). Writes OUT_DIR/runs/* and
# OUT_DIR/levers.{md,json} (every run present under OUT_DIR/runs, earlier calls' runs included).
#   INPUTS  space-separated: rpy0_149 (choice), rpy150_269 (report), rpy0_269, desk, 7s0_99 (choice),
#           7s100_199 (report), 7s0_199
#   MODES   space-separated: off (today's defaults), sdfnoise:REF (the hand-over sdf's rows weighed by the depth
#           noise beyond REF m), sdfminw:W (sdf's voxels seen fewer than W times count as unobserved),
#           trunc:REF:F (integrate.truncation_depth_ref_m REF, truncation_min_fraction F); several joined by
#           + (e.g. sdfnoise:1.5+trunc:3:0.5), wdepth:REF (integrate.weight_depth_ref_m REF), sdfkey:KEY:VALUE (any
#           key of the hand-over sdf, e.g. sdfkey:robust_sdf:student_t), key:KEY:VALUE (a top-level key of the
#           configuration, e.g. key:wide_basin_without_prior:false), window:N:SCALE[:TRACK] (keyframe window
#           edges to the N-1 keyframes before the previous one, information times SCALE, the tracked keyframe steps
#           kept with information times TRACK, 0 when left out: loop_closure.window_*), skey:SECTION.KEY:VALUE (a
#           key of a section, e.g. skey:volume.voxel_m:0.008), rcmw:W (the tracking raycast's raycast.min_weight
#           W: surfaces seen fewer than W times are not tracked against)
# e.g. HF_BIN=/tmp/hf bash scripts/bench_ate_levers.sh out/levers "rpy0_149 7s0_99" "off trunc:3:0.5"
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/bench_lib.sh
bench_init bench_ate_levers "${1:-out/bench_ate_levers}"
inputs="${2:-rpy0_149 7s0_99}"
modes="${3:-off}"

bench_fr1_rpy_0_269        # $work/tum_fr1_rpy_frames0_269
bench_seven_scenes_halves  # $work/7scenes_frames0_99, $work/7scenes_frames100_199
declare -A input_dir=([rpy0_149]="$shared/tum_fr1_rpy_first150" [rpy150_269]="$shared/tum_fr1_rpy_frames150_269"
                      [rpy0_269]="$work/tum_fr1_rpy_frames0_269" [desk]="$shared/tum_fr1_desk_9frames"
                      [7s0_99]="$work/7scenes_frames0_99" [7s100_199]="$work/7scenes_frames100_199"
                      [7s0_199]="$(realpath "$shared/7scenes_tsdf_fusion_first200")")

for key in $inputs; do
  for mode in $modes; do
    parts=()
    IFS=+ read -r -a levers <<< "$mode"
    for one in "${levers[@]}"; do
      IFS=: read -r lever a b <<< "$one"
      case "$lever" in
        off) ;;
        sdfnoise) parts+=("{\"depth_only_registration_options\": {\"depth_noise_ref_m\": $a}}") ;;
        sdfminw) parts+=("{\"depth_only_registration_options\": {\"min_voxel_weight\": $a}}") ;;
        sdfkey) [[ "$b" =~ ^-?[0-9.]+$ ]] || b="\"$b\""  # a number as it is, else a string
                parts+=("{\"depth_only_registration_options\": {\"$a\": $b}}") ;;
        key) [[ "$b" =~ ^(-?[0-9.]+|true|false)$ ]] || b="\"$b\""
             parts+=("{\"$a\": $b}") ;;
        rcmw) parts+=("{\"raycast\": {\"min_weight\": $a}}") ;;
        skey) IFS=: read -r _ path value <<< "$one"  # skey:SECTION.KEY:VALUE, e.g. skey:volume.voxel_m:0.008
              parts+=("{\"${path%%.*}\": {\"${path#*.}\": $value}}") ;;
        wdepth) parts+=("{\"integrate\": {\"weight_depth_ref_m\": $a}}") ;;
        trunc) parts+=("{\"integrate\": {\"truncation_depth_ref_m\": $a, \"truncation_min_fraction\": $b}}") ;;
        window) IFS=: read -r _ n scale track <<< "$one"  # window:N:SCALE[:TRACK]
                parts+=("{\"loop_closure\": {\"window_keyframes\": $n, \"window_information_scale\": $scale, \"window_tracking_information_scale\": ${track:-0}}}") ;;
        *) echo "bench_ate_levers: unknown mode '$one'" >&2; exit 1 ;;
      esac
    done
    # The levers' sections merged into one config (sections do not overlap but for the hand-over's options).
    python3 -c 'import json, sys
c = {}
for p in sys.argv[1:]:
    for k, v in json.loads(p).items():
        if isinstance(v, dict): c.setdefault(k, {}).update(v)
        else: c[k] = v
print(json.dumps(c))' "${parts[@]}" > "$work/c.json"
    bench_run "${key}__${mode//:/_}" "${input_dir[$key]}" --config "$work/c.json"
  done
done

bench_ate_table levers mode
