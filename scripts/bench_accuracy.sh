#!/usr/bin/env bash
# The accuracy benchmark: every loop model and `none`, N runs each at the camera's rate (`run --rate 1`, as a
# bag played at 1x, one run at a time so that each has the machine), on whole rendered routes 06, 05 and 00
# and on the real KITTI frames, scored beside ORB-SLAM2's runs on the same data
# (../shared/reference/orbslam2). Prints one table per sequence (eval-slam's accuracy table: ATE and t_rel
# median and range, loops wrong by distance or relative pose, revisits closed in every run, lost frames).
#   scripts/bench.sh accuracy [--routes "06 05 00 real06 sample00"] [--runs 3] [--detectors all,none]
#                             [--config <yaml>] [--out <dir>] [--lockstep]
# The renders are those of the reference (seed 7, KITTI 00's calibration, 10 Hz), made once into
# .build/bench/renders. A whole run takes hours (06: 110 s a run, 05: 276 s, 00: 454 s); pick routes.
# Routes 06rigid, 05rigid, 00rigid are the same routes rendered with one road surface for the whole world
# (`render --rigid-ground`; the reference's renders have a ground plane that follows each camera, see
# docs/renderer.md). ORB-SLAM2 never ran on them, so they are scored alone.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
routes="06 05 00 real06 sample00" runs=3 detectors=all,none config="" out="$BINLOOP_BUILD/bench/accuracy" pace="--rate 1"
while [ $# -gt 0 ]; do
  case "$1" in
    --routes) routes="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --detectors) detectors="$2"; shift 2 ;;
    --config) config="$(realpath "$2")"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --lockstep) pace="--lockstep"; shift ;;
    *) echo "bench accuracy: unknown option $1 (--routes, --runs, --detectors, --config, --out, --lockstep)" >&2; exit 2 ;;
  esac
done
shared="$BINLOOP_ROOT/../shared"
reference="$shared/reference/orbslam2"
renders="$BINLOOP_BUILD/bench/renders"
bl="$BINLOOP_ROOT/scripts/binloop"
[ -d "$reference" ] || { echo "bench accuracy: $reference is not there (ORB-SLAM2's runs to compare against)" >&2; exit 1; }

declare -A last_frame=([06]=1100 [05]=2760 [00]=4540)
for r in $routes; do
  ref=""
  case "$r" in
    06|05|00|06rigid|05rigid|00rigid)
      route="${r%rigid}" seq="$renders/r$r" ground=()
      [ "$route" != "$r" ] && ground=(--rigid-ground)
      if [ ! -f "$seq/poses.txt" ] || [ "$(wc -l <"$seq/poses.txt")" -ne $((last_frame[$route] + 1)) ]; then
        echo "bench accuracy: rendering route $route (seed 7, as the reference's renders${ground:+, rigid ground}) into $seq"
        "$bl" render --route "$shared/data/kitti/poses/$route.txt" --start 0 --end "${last_frame[$route]}" --step 1 \
          --seed 7 "${ground[@]}" --out "$seq" --force 2> >(grep -v 'libpng warning' >&2) >/dev/null
      fi
      [ "$route" = "$r" ] && ref="$reference/render_$r" ;;
    real06) seq="$shared/data/kitti/real_06_000_050" ref="$reference/real_06_000_050" ;;
    sample00) seq="$shared/data/kitti/sample_00" ref="$reference/real_sample_00" ;;
    *) echo "bench accuracy: unknown route $r (06, 05, 00, 06rigid, 05rigid, 00rigid, real06, sample00)" >&2; exit 2 ;;
  esac
  echo
  echo "== $r: $seq ($runs runs per detector, $pace)"
  args=(--sequence "$seq" --out "$out/$r" --detectors "$detectors" --runs "$runs" --jobs 1)
  [ -n "$ref" ] && args+=(--reference "$ref")
  [ "$pace" = --lockstep ] && args+=(--lockstep) || args+=(--run-args "--rate 1")
  [ -n "$config" ] && args+=(--config "$config")
  # The accuracy table only; each run's own row is in $out/$r/summary.csv.
  "$bl" eval-slam "${args[@]}" 2> >(grep -v 'libpng warning' >&2) | sed -n '/^accuracy over/,$p'
done
