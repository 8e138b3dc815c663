#!/usr/bin/env bash
# The soak benchmark: a rendered route played at 1x in a loop (rosbag play -l) through kitti_stereo.launch
# for --minutes, watched by scripts/soak_monitor.py: tracking found again after every wrap, tracking's time
# and the stamp-to-pose delay (p95, first and last --window minutes), the manager's resident memory against
# the keyframes it holds, the largest message of every /binloop topic early and late. Not a test: it prints
# a table and writes <out>/soak.json.
# --split runs kitti_stereo_split.launch respawn:=true instead (each stage its own process, local mapping
# autosaving every 10 keyframes): the memory is then the four processes' together.
#   scripts/bench.sh soak [--minutes 60] [--route 06] [--end 1100] [--detector hmvlad] [--window 10] [--split]
#                         [--out <dir>]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
minutes=60 route=06 end=1100 detector=hmvlad window=10 split=0 out="$BINLOOP_BUILD/bench/soak"
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) minutes="$2"; shift 2 ;;
    --route) route="$2"; shift 2 ;;
    --end) end="$2"; shift 2 ;;
    --detector) detector="$2"; shift 2 ;;
    --window) window="$2"; shift 2 ;;
    --split) split=1; shift ;;
    --out) out="$2"; shift 2 ;;
    *) echo "bench soak: unknown option $1 (--minutes, --route, --end, --detector, --window, --split, --out)" >&2
       exit 2 ;;
  esac
done
shared="$BINLOOP_ROOT/../shared"
bl="$BINLOOP_ROOT/scripts/binloop"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
seq="$out/r${route}_0_$end"
bag="$out/r${route}_0_$end.bag"
# The accuracy benchmark's render of the whole route is the same one (seed 7): no need to render it again.
whole="$BINLOOP_BUILD/bench/renders/r$route"
if [ ! -f "$seq/poses.txt" ] && [ -f "$whole/poses.txt" ] && [ "$(wc -l <"$whole/poses.txt")" -eq $((end + 1)) ]; then
  seq="$whole"
fi
if [ ! -f "$seq/poses.txt" ]; then
  echo "bench soak: rendering route $route frames 0-$end (seed 7) into $seq"
  "$bl" render --route "$shared/data/kitti/poses/$route.txt" --start 0 --end "$end" --step 1 --seed 7 --out "$seq" \
    2> >(grep -v 'libpng warning' >&2) >/dev/null
fi
[ -f "$bag" ] || "$bl" kitti2bag "$seq" "$bag" >/dev/null

set --  # catkin's setup.bash reads the positional arguments
set +u
source "$BINLOOP_WS/devel/setup.bash"
set -u
export PATH="/usr/bin:$PATH"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT
if ! rosnode list >/dev/null 2>&1; then
  roscore >"$out/roscore.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 100); do rosnode list >/dev/null 2>&1 && break; sleep 0.1; done
fi
rosparam set /use_sim_time true
if [ "$split" = 1 ]; then
  launch=(kitti_stereo_split.launch respawn:=true) processes=4 pattern='nodelet standalone binloop/'
else
  launch=(kitti_stereo.launch) processes=1 pattern='nodelet manager'
fi
roslaunch binloop "${launch[@]}" detector:="$detector" use_sim_time:=true >"$out/graph.log" 2>&1 &
pids+=($!)
graph=()
for _ in $(seq 300); do
  if rostopic list 2>/dev/null | grep -qx /binloop/tracked_frame; then
    mapfile -t graph < <(pgrep -f "$pattern")
    [ "${#graph[@]}" -ge "$processes" ] && break
  fi
  sleep 0.1
done
[ "${#graph[@]}" -ge "$processes" ] || { echo "bench soak: the graph is not running (see $out/graph.log)" >&2; exit 1; }
echo "bench soak: $bag looped at 1x for $minutes min (detector $detector, ${launch[0]}, pids ${graph[*]});" \
  "graph log $out/graph.log"
rosbag play --clock -q -l -d 1 "$bag" >"$out/play.log" 2>&1 &
pids+=($!)
/usr/bin/python3 "$BINLOOP_ROOT/scripts/soak_monitor.py" --minutes "$minutes" $(printf -- '--pid %s ' "${graph[@]}") --window-min "$window" \
  --out "$out" | tee "$out/soak.txt"
