# Sourced by the other scripts: where things are, and an environment that works with Debian's ROS.
# Debian's ROS needs the system python (the machine's `python3` may be a pyenv shim without catkin_pkg).
BINLOOP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BINLOOP_BUILD="$BINLOOP_ROOT/.build"
BINLOOP_WS="$BINLOOP_BUILD/ws"
BINLOOP_CORE_BUILD="$BINLOOP_BUILD/core"
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
BINLOOP_JOBS="${BINLOOP_JOBS:-$(nproc)}"
# ccache (scripts/build.sh) keeps its cache in the git-ignored build folder, writable wherever the build is.
export CCACHE_DIR="${CCACHE_DIR:-$BINLOOP_BUILD/ccache}"
