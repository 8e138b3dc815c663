#!/usr/bin/env bash
# Re-makes docs/rviz_06.png: rendered KITTI route 06 (every 2nd frame) played at 1x through the nodelet graph
# (kitti_stereo.launch, vlad) with rviz under Xvfb, seen from above with the whole route in view.
#   docs/make_rviz_shot.sh [work_dir]     (default /tmp/binloop_rviz_shot; needs ../shared/data)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
work="${1:-/tmp/binloop_rviz_shot}"
bl="$root/scripts/binloop"
mkdir -p "$work"
[ -d "$work/seq06" ] || "$bl" render --route "$root/../shared/data/kitti/poses/06.txt" \
  --times "$root/../shared/data/kitti/times/06.txt" --calib kitti04 --out "$work/seq06" --step 2
[ -f "$work/06.bag" ] || "$bl" kitti2bag "$work/seq06" "$work/06.bag"
# binloop.rviz's top view, moved and scaled so that route 06 (460 m along, 23 m across) fills the window.
sed -e 's/^      Scale: .*/      Scale: 1.9/' -e 's/^      X: .*/      X: 72/' -e 's/^      Y: .*/      Y: 8/' \
  -e 's/^      Angle: .*/      Angle: 0/' "$root/rviz/binloop.rviz" >"$work/06.rviz"
rm -rf "$work/ros"
"$bl" run-bag "$work/06.bag" --out "$work/ros" --detector vlad --screenshot "$work/shot.png" \
  --launch-args "rviz_config:=$work/06.rviz"
convert "$work/shot.png" -crop 1400x900+0+0 +repage "$root/docs/rviz_06.png"
echo "docs/rviz_06.png made from $work/shot.png"
