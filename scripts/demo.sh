#!/usr/bin/env bash
# Set-up, build, and the main job on a built-in default:
#   scripts/demo.sh                    renders a stereo sequence with a loop (KITTI route 06 when
#                                      ../shared/data is there, else the built-in block loop), turns it
#                                      into a ROS bag and shows what the bag holds
#   scripts/demo.sh <kitti_seq_dir>    the same with your own KITTI odometry sequence (no rendering)
# Output goes to .build/demo/ (git-ignored).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
"$BINLOOP_ROOT/scripts/setup.sh"
"$BINLOOP_ROOT/scripts/build.sh" >"$BINLOOP_BUILD/demo-build.log" 2>&1 || {
  tail -30 "$BINLOOP_BUILD/demo-build.log"; echo "demo: build failed (log: $BINLOOP_BUILD/demo-build.log)"; exit 1; }
out="$BINLOOP_BUILD/demo"
mkdir -p "$out"
bl="$BINLOOP_ROOT/scripts/binloop"

if [ $# -ge 1 ]; then
  seq="$1"
  echo "demo: using KITTI sequence $seq"
else
  seq="$out/sequence"
  route="$BINLOOP_ROOT/../shared/data/kitti/poses/06.txt"
  times="$BINLOOP_ROOT/../shared/data/kitti/times/06.txt"
  if [ -f "$route" ]; then
    echo "demo: rendering KITTI route 06 (every 2nd frame; the car returns to its start after frame 827)"
    "$bl" render --route "$route" --times "$times" --out "$seq" --step 2 --force
  else
    echo "demo: no KITTI routes in ../shared/data; rendering the built-in loop (1.3 laps of a 120x200 m block)"
    "$bl" render --route loop --out "$seq" --step 2 --force
  fi 2> >(grep -v 'libpng warning' >&2)
fi

"$bl" kitti2bag "$seq" "$out/demo.bag" --force
rosbag info "$out/demo.bag"
echo
echo "demo: done. Sequence (KITTI layout): $seq   bag: $out/demo.bag"
echo "      play it with: roscore & rosbag play $out/demo.bag"
