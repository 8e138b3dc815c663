#!/usr/bin/env bash
# Set-up, build, and the main job on a built-in default:
#   scripts/demo.sh                    renders a stereo sequence with a loop (KITTI route 06 when
#                                      ../shared/data is there, else the built-in block loop), turns it
#                                      into a ROS bag, shows what the bag holds, runs the SLAM with loop
#                                      closing over it once per loop model and once without (eval-slam:
#                                      ATE, t_rel, loops accepted and correct, one plot), plays the bag
#                                      through the ROS nodelet graph (kitti_stereo.launch, rviz under Xvfb:
#                                      trajectory, loop log, plot, screenshot), and scores the five loop
#                                      models' detection alone (eval-loops)
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

# Loop detection. hbow's vocabulary (26 MB) is not tracked; it is made once from rendered route 08, and
# made again when it predates model files that record their extractor (version < 3: trained on OpenCV's
# ORB, which the SLAM's descriptors do not match).
models=fabmap,vlad,hmvlad,vladpq
hbow_file="$BINLOOP_ROOT/vocab/kitti08/hbow.bin"
if [ -f "$hbow_file" ] && [ "$(od -An -tu4 -j8 -N4 "$hbow_file" | tr -d ' ')" -lt 3 ]; then
  echo "demo: $hbow_file was trained with an older extractor; making it again"
  rm -f "$hbow_file"
fi
if [ ! -f "$hbow_file" ] && [ -f "$BINLOOP_ROOT/../shared/data/kitti/poses/08.txt" ]; then
  echo "demo: making the hbow vocabularies once (renders route 08, about 6 minutes): vocab/make_vocab.sh hbow"
  "$BINLOOP_ROOT/vocab/make_vocab.sh" hbow 2> >(grep -v 'libpng warning' >&2)
fi
[ -f "$BINLOOP_ROOT/vocab/kitti08/hbow.bin" ] && models="hbow,$models"

# The SLAM with loop closing, once per loop model and once without (lock-step: each keyframe is mapped and
# searched for loops before the next frame), scored against the sequence's poses in one table and one plot.
echo
if [ -f "$seq/poses.txt" ]; then
  echo "demo: SLAM with loop closing over $seq, once per model ($models) and once without (none)"
  (cd "$BINLOOP_ROOT" && "$bl" eval-slam --sequence "$seq" --detectors "$models,none" --lockstep \
    --config config/kitti.yaml --out "$out/slam") 2> >(grep -v 'libpng warning' >&2)
else
  first="${models%%,*}"
  echo "demo: SLAM with loop closing ($first) over $seq (no poses.txt: not scored)"
  (cd "$BINLOOP_ROOT" && "$bl" run "$seq" --out "$out/slam/$first" --detector "$first" --lockstep \
    --config config/kitti.yaml) 2> >(grep -v 'libpng warning' >&2)
fi

# The whole system through ROS: the bag played at its own rate through the four nodelets in one manager, rviz
# under Xvfb for a screenshot, and the trajectory the graph published scored and drawn.
first="${models%%,*}"
echo
echo "demo: the ROS graph (kitti_stereo.launch, detector $first) over $out/demo.bag, played at 1x"
rm -rf "$out/ros"
"$bl" run-bag "$out/demo.bag" --out "$out/ros" --detector "$first" --screenshot "$out/ros/rviz.png"
if [ -f "$seq/poses.txt" ]; then
  "$bl" eval-traj --gt "$seq/poses.txt" --est "$out/ros/trajectory.tum.txt" --times "$seq/times.txt" \
    --stamp-offset 1 --plot "$out/ros/trajectory.png"
fi

echo
if [ -f "$seq/poses.txt" ]; then
  echo "demo: loop detection with $models (vocabularies trained on rendered route 08)"
  (cd "$BINLOOP_ROOT" && "$bl" eval-loops --sequence "$seq" --models "$models" --vocab-dir vocab/kitti08 \
    --window 150 --out "$out/loops") 2> >(grep -v 'libpng warning' >&2)
else
  echo "demo: $seq has no poses.txt, so there is no ground truth to score loop detection against"
fi
echo
echo "demo: done. Sequence (KITTI layout): $seq   bag: $out/demo.bag   loops: $out/loops/ (summary.csv, pr.png)"
echo "      SLAM: $out/slam/ (summary.csv, trajectories.png; per model: trajectory.kitti.txt, loops.csv, summary.json)"
echo "      ROS graph: $out/ros/ (trajectory.kitti.txt, loops.csv, summary.json, trajectory.png, rviz.png, graph.log)"
echo "      play it yourself: roslaunch binloop kitti_stereo.launch bag:=$out/demo.bag detector:=$first rviz:=true"
