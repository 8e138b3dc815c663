#!/usr/bin/env bash
# Builds binloop into the git-ignored .build/: the catkin workspace .build/ws (package symlinked into
# ws/src) and the ROS-free core build .build/core. Incremental: a second run rebuilds only what changed.
#   scripts/build.sh            both
#   scripts/build.sh --core     only the ROS-free core and its tests
#   scripts/build.sh --ros      only the catkin package
#   scripts/build.sh --configure-core   only configure the core (its compile_commands.json, for clang-tidy)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"

what="${1:-all}"
mkdir -p "$BINLOOP_WS/src" "$BINLOOP_CORE_BUILD"

# Both builds compile the core library from the same sources; through ccache the catkin build takes the
# core build's objects (its extra ROS defines change nothing the core preprocesses): 15 s instead of ~2 min.
# Its cache is in the build folder (scripts/env.sh, CCACHE_DIR).
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

configure_core() {
  # Warnings are errors in the project's own builds (cmake/binloop_core.cmake, BINLOOP_WERROR).
  cmake -S "$BINLOOP_ROOT/cmake/core_only" -B "$BINLOOP_CORE_BUILD" -DCMAKE_BUILD_TYPE=Release -DBINLOOP_WERROR=ON \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON "${launcher[@]}" >/dev/null
}
if [ "$what" = --configure-core ]; then
  configure_core
  exit
fi

if [ "$what" = all ] || [ "$what" = --core ]; then
  echo "build: core (no ROS) -> $BINLOOP_CORE_BUILD"
  configure_core
  cmake --build "$BINLOOP_CORE_BUILD" -j "$BINLOOP_JOBS"
fi

if [ "$what" = all ] || [ "$what" = --ros ]; then
  echo "build: catkin package -> $BINLOOP_WS"
  ln -sfn "$BINLOOP_ROOT" "$BINLOOP_WS/src/binloop"
  cd "$BINLOOP_WS"
  catkin_make -j"$BINLOOP_JOBS" -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DCATKIN_ENABLE_TESTING=ON -DBINLOOP_WERROR=ON "${launcher[@]}"
  # Test binaries too, so that `scripts/test.sh` only runs them.
  catkin_make -j"$BINLOOP_JOBS" tests
fi
