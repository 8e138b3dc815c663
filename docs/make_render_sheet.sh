#!/usr/bin/env bash
# Re-makes docs/render_06.png: rendered frames of KITTI route 06, including a revisit pair
# (route frame 900 is within 6 m of frame 74 in ../shared/data/kitti/loop_gt/06.txt).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
route="$root/../shared/data/kitti/poses/06.txt"
for f in 74 900 300 600; do
  "$root/scripts/binloop" render --route "$route" --out "$tmp/$f" --start $f --end $f >/dev/null 2>&1
done
"$root/scripts/binloop" contact-sheet --out "$root/docs/render_06.png" --columns 2 --scale 0.5 \
  --image "$tmp/74/image_0/000000.png:route 06, frame 74 (left)" \
  --image "$tmp/900/image_0/000000.png:route 06, frame 900 (left): revisits frame 74" \
  --image "$tmp/300/image_0/000000.png:route 06, frame 300 (left)" \
  --image "$tmp/300/image_1/000000.png:route 06, frame 300 (right)" \
  --image "$tmp/600/image_0/000000.png:route 06, frame 600 (left)" \
  --image "$tmp/600/image_1/000000.png:route 06, frame 600 (right)"
