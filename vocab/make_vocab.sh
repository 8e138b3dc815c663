#!/bin/bash
# Re-makes the shipped vocabularies exactly as they were made (docs/loop_models.md, "Vocabularies").
# Every image goes through binloop's ORB-SLAM2-style extractor with the SLAM's settings (config/kitti.yaml's
# orb: 2000 features, scale 1.2, 8 levels, FAST 20/7, 30-px cells, Gaussian BRIEF tests), which `train`
# uses by default, so the SLAM and `eval-loops` feed these models the descriptors they were trained on; each
# model file records those settings in its header, and loaders refuse a model trained with others
# (--force-extractor). The photos set uses ORB's learned BRIEF tests instead (`--pattern orb`): on real
# images every model but fabmap finds more loops with them; eval-loops follows what the files record.
#   vocab/kitti08/<model>.bin  — every model, trained on rendered KITTI route 08 only (every 8th frame, full
#                                size 1241x376, as the SLAM sees its keyframes), as the thesis trained on
#                                KITTI 08.
#   vocab/kitti08/hbow_k8l5.bin — a small hbow vocabulary (k=8, L=5, 1.6 MB) from the same images: what
#                                relocalisation uses by default, tracked so that a plain clone has it.
#   vocab/photos/<model>.bin   — every model for real images: the Debian photos (opencv-doc, python3-skimage,
#                                one image per plasma-workspace-wallpapers wallpaper) except those of the
#                                real-image loop sets (data/loop_sets/*.txt), plus every 16th frame of
#                                rendered route 08; longer side scaled to 1024 first (--max-side 1024) and
#                                ORB's learned BRIEF tests (--pattern orb); eval-loops queries the same way.
#   vocab/photos/hbow_k8l5.bin  — a small hbow vocabulary (k=8, L=5) from the same photos: relocalisation
#                                for a camera run with ORB's learned tests (docs/robot.md), tracked.
# Needs ../shared/data/kitti/poses/08.txt for the route; takes about 15 minutes on 2 cores.
# The hbow files (21-27 MB) are too large to track and are made here; the other four are tracked.
# `vocab/make_vocab.sh hbow` makes only the two hbow files (render of 08 plus about a minute of training).
# `vocab/make_vocab.sh photos` makes only vocab/photos/, `vocab/make_vocab.sh kitti08` only vocab/kitti08/.
# BINLOOP_TOOLS=<dir> runs the tools from <dir> instead of scripts/binloop (a build of the core alone).
# BINLOOP_VOCAB_OUT=<dir> writes <dir>/kitti08 and <dir>/photos instead of vocab/ (to compare before replacing).
set -euo pipefail
sets="hbow photos kitti08"
which="${1:-}"
if [ -n "$which" ] && ! grep -qw -- "$which" <<<"$sets"; then
  echo "make_vocab.sh: unknown set '$which' (none for every set, or ${sets// /, })" >&2
  exit 2
fi
source "$(dirname "$0")/../scripts/env.sh"
cd "$BINLOOP_ROOT"
bl() {
  if [ -n "${BINLOOP_TOOLS:-}" ]; then "$BINLOOP_TOOLS/$1" "${@:2}"; else scripts/binloop "$@"; fi
}
work="${BINLOOP_VOCAB_WORK:-$BINLOOP_BUILD/vocab-work}"
seq08="$work/render08"
shared="${BINLOOP_SHARED_DATA:-$BINLOOP_ROOT/../shared/data}"
if [ ! -f "$seq08/poses.txt" ]; then
  bl render --route "$shared/kitti/poses/08.txt" --times "$shared/kitti/times/08.txt" \
    --calib kitti04 --out "$seq08" --force
fi
out="${BINLOOP_VOCAB_OUT:-vocab}"
mkdir -p "$out/kitti08" "$out/photos"
models="hbow fabmap vlad hmvlad vladpq"
[ "$which" = hbow ] && models=hbow
kitti_models="$models"
[ "$which" = photos ] && kitti_models=""
# The VLAD family's words, larger than the thesis' (VLAD 4, HMVLAD 2 and 4): with either BRIEF pattern,
# 64 words (HMVLAD 8 and 64) raise R@100P on every rendered route and on the real loop sets (docs/decisions.md,
# "64 VLAD words"). Each word's residuals are rotated onto their principal directions and whitened (LCS-PCA)
# before the signs are taken: on real images the plain signs sit close to coin flips. 96 directions a word,
# 64 for vladpq, whose codebooks would take its file past the 2 MB a tracked file may have
# (docs/decisions.md, "LCS-PCA shipped in 96 and 64 dimensions").
vlad_options() {
  case "$1" in
    vlad) echo "--k 64 --pca 96" ;;
    vladpq) echo "--k 64 --pca 64" ;;
    hmvlad) echo "--k 8 --pca 96" ;;
  esac
}
# train_set <images> <out dir> <models> [train options]: each model, and the small hbow that relocalisation
# uses beside them (k=8, L=5, tracked; not made by `make_vocab.sh hbow`, which makes the large ones only).
train_set() {
  local images=$1 dir=$2 set_models=$3 extra
  shift 3
  [ -n "$set_models" ] || return 0
  for m in $set_models; do
    extra=$(vlad_options "$m")
    bl train "$m" --images "$images" "$@" --seed 1 $extra --out "$dir/$m.bin"
  done
  if [ "$which" != hbow ]; then
    bl train hbow --images "$images" "$@" --seed 1 --k 8 --levels 5 --out "$dir/hbow_k8l5.bin"
  fi
}
train_set "$seq08" "$out/kitti08" "$kitti_models" --every 8
[ "$which" = kitti08 ] && exit 0
stage="$work/photos"
rm -rf "$stage" && mkdir -p "$stage"
i=0
# Images of the real-image loop sets are evaluation data: never train on them.
held_out=$(cat data/loop_sets/*.txt | sed 's/#.*//' | tr -s ' \t' '\n' | grep '/' || true)
link() {
  if grep -qxF "$1" <<<"$held_out"; then return; fi
  ln -s "$1" "$stage/$(printf %04d $i).${1##*.}"; i=$((i + 1))
}
for f in /usr/share/doc/opencv-doc/examples/data/*.{jpg,png} /usr/lib/python3/dist-packages/skimage/data/*.{jpg,png}; do
  # skimage ships truncated.jpg on purpose (a broken file for its own tests)
  [ -f "$f" ] && [ "$(basename "$f")" != truncated.jpg ] && link "$f"
done
for w in /usr/share/wallpapers/*/contents/images; do
  # One picture per wallpaper: the first 1920-wide version, else the first file.
  f=$(ls "$w"/1920x* 2>/dev/null | head -1 || true)
  [ -n "$f" ] || f=$(ls "$w"/* | head -1)
  link "$f"
done
n=0
for f in "$seq08"/image_0/*.png; do
  [ $((n % 16)) -eq 0 ] && link "$f"
  n=$((n + 1))
done
echo "make_vocab: $i training images for vocab/photos (loop-set images left out)"
train_set "$stage" "$out/photos" "$models" --max-side 1024 --pattern orb --skip-unreadable
