#!/usr/bin/env bash
# Builds and runs the benchmarks (bench/*.cpp); each prints markdown tables. Not part of the test suite.
#   scripts/bench.sh            all
#   scripts/bench.sh render     only bench/render_bench.cpp
#   scripts/bench.sh place vocab   only bench/place_bench.cpp, passing it "vocab"
#   scripts/bench.sh accuracy [...]   the SLAM at 1x beside ORB-SLAM2's runs (scripts/bench_accuracy.sh; hours)
#   scripts/bench.sh soak [...]       a bag looped at 1x through the graph for an hour (scripts/bench_soak.sh)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
if [ "${1:-}" = accuracy ]; then exec "$BINLOOP_ROOT/scripts/bench_accuracy.sh" "${@:2}"; fi
if [ "${1:-}" = soak ]; then exec "$BINLOOP_ROOT/scripts/bench_soak.sh" "${@:2}"; fi
"$BINLOOP_ROOT/scripts/build.sh" --ros >/dev/null
cd "$BINLOOP_ROOT"  # benchmarks find vocab/ and ../shared/data from the repository root
for b in "$BINLOOP_WS"/devel/lib/binloop/bench/bench_*; do
  name=$(basename "$b")
  if [ $# -gt 0 ] && [[ "$name" != "bench_$1"* ]]; then continue; fi
  echo "== $name"
  short="${name#bench_}"
  # Each benchmark may write its headline numbers here, to compare runs (e.g. .build/bench/place.json).
  BINLOOP_BENCH_JSON="$BINLOOP_BUILD/bench/${short%_bench}.json" "$b" "${@:2}" 2> >(grep -v 'libpng warning' >&2)
done
