#!/usr/bin/env bash
# run-bag: plays a bag (kitti2bag's topics) through the binloop nodelet graph and writes the offline runner's
# files (trajectory, loops.csv, summary.json) into --out, so the ROS path and `scripts/binloop run` can be
# compared. Starts a master if none runs (on ROS_MASTER_URI's port); stops everything it started. The graph and
# the recorder come from whichever space is sourced (scripts/binloop: the build's devel space; a test sources
# an install space instead).
#   scripts/binloop run-bag <bag> --out <dir> [--detector hmvlad] [--rate 1.0] [--split] [--lockstep]
#                           [--launch-args "arg:=value ..."] [--screenshot shot.png]
# --lockstep: tracking waits for local mapping after each keyframe, as `run --lockstep` (for comparisons).
# --screenshot: also runs rviz (under Xvfb when there is no display) and saves its window after the bag.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"

usage() { sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; }
bag="" out="" detector="hmvlad" rate="1.0" launch="kitti_stereo.launch" extra="" shot=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --detector) detector="$2"; shift 2 ;;
    --rate) rate="$2"; shift 2 ;;
    --split) launch="kitti_stereo_split.launch"; shift ;;
    --lockstep) extra="$extra lockstep:=true"; shift ;;
    --launch-args) extra="$2"; shift 2 ;;
    --screenshot) shot="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "run-bag: unknown option $1" >&2; usage >&2; exit 2 ;;
    *) bag="$1"; shift ;;
  esac
done
[ -n "$bag" ] && [ -n "$out" ] || { usage >&2; exit 2; }
[ -f "$bag" ] || { echo "run-bag: no bag at $bag" >&2; exit 1; }
bag="$(cd "$(dirname "$bag")" && pwd)/$(basename "$bag")"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

if [ -n "$shot" ]; then
  case "$shot" in /*) ;; *) shot="$PWD/$shot" ;; esac
  if [ -z "${DISPLAY:-}" ]; then
    Xvfb :97 -screen 0 1600x1000x24 >"$out/xvfb.log" 2>&1 &
    pids+=($!)
    export DISPLAY=:97
    sleep 1
  fi
  extra="$extra rviz:=true"
fi
if ! rosnode list >/dev/null 2>&1; then
  port="${ROS_MASTER_URI:-http://localhost:11311}"; port="${port##*:}"; port="${port%%/*}"
  roscore -p "$port" >"$out/roscore.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 100); do rosnode list >/dev/null 2>&1 && break; sleep 0.1; done
fi
rosparam set /use_sim_time true
# shellcheck disable=SC2086
roslaunch binloop "$launch" detector:="$detector" use_sim_time:=true $extra >"$out/graph.log" 2>&1 &
graph=$!
pids+=("$graph")
# The recorder of the sourced space (the first prefix that has one); not rosrun, which in a devel space also
# searches the source folder, where the checkout's own .build/ holds more copies.
recorder_bin=""
IFS=: read -r -a prefixes <<<"${CMAKE_PREFIX_PATH:-}"
for p in "${prefixes[@]}"; do
  [ -x "$p/lib/binloop/record-run" ] && { recorder_bin="$p/lib/binloop/record-run"; break; }
done
[ -n "$recorder_bin" ] || { echo "run-bag: no lib/binloop/record-run on CMAKE_PREFIX_PATH (source a setup.bash)" >&2; exit 1; }
"$recorder_bin" --out "$out" >"$out/record.log" 2>&1 &
recorder=$!
pids+=("$recorder")
# Wait for the Tracking nodelet (it advertises tracked_frame once its inputs are subscribed, whatever their
# namespace and transport). The player starts paused and runs once every subscriber of its topics has
# connected to it: a fixed delay is not enough on a loaded machine, and a pair sent before is lost.
for _ in $(seq 300); do
  rostopic list 2>/dev/null | grep -qx /binloop/tracked_frame && break
  sleep 0.1
done
echo "run-bag: playing $bag at rate $rate through $launch (detector $detector); graph log $out/graph.log"
player=binloop_bag_player_$$  # its own name: a second run-bag on the same master must not replace it
rosbag play --clock -q --pause -r "$rate" "$bag" __name:=$player &
play=$!
pids+=("$play")
"$(dirname "${BASH_SOURCE[0]}")/wait_bag_connections.py" "$player" "$bag" 30 || echo "run-bag: playing anyway" >&2
for try in $(seq 50); do
  rosservice call "/$player/pause_playback" "data: false" >/dev/null 2>&1 && break
  kill -0 "$play" 2>/dev/null || { echo "run-bag: rosbag play ended before it played (see above)" >&2; exit 1; }
  [ "$try" = 50 ] && { echo "run-bag: could not start the player (/$player/pause_playback)" >&2; exit 1; }
  sleep 0.2
done
wait "$play"
# The recorder writes once the graph has been quiet for 3 s (it may still be working through queued pairs).
kill -INT "$recorder"; wait "$recorder" || true
if [ -n "$shot" ]; then
  sleep 2  # rviz draws the last messages
  import -window root "$shot" && echo "run-bag: rviz screenshot in $shot"
fi
kill -INT "$graph"; wait "$graph" || true
cat "$out/record.log"
echo "run-bag: results in $out"
