#!/usr/bin/env bash
# Set-up, build and every test: the ROS-free core tests (plain CMake + ctest, including the check that the
# core uses no ROS) and the ROS tests (catkin gtests and rostests). Exits non-zero on any failure and ends
# with one summary line "binloop: N passed, N failed, N skipped".
#   scripts/test.sh              everything
#   scripts/test.sh --no-setup   skip the apt step (packages already installed)
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
log="$BINLOOP_BUILD/test-logs"

if [ "${1:-}" != --no-setup ]; then
  "$BINLOOP_ROOT/scripts/setup.sh" || { echo "test: set-up failed"; exit 1; }
fi
"$BINLOOP_ROOT/scripts/build.sh" || { echo "test: build failed"; echo "binloop: 0 passed, 1 failed"; exit 1; }
mkdir -p "$log"

echo "== core tests (no ROS)"
(cd "$BINLOOP_CORE_BUILD" && ctest --output-on-failure -j "$BINLOOP_JOBS" --timeout 900) 2>&1 | tee "$log/core.txt"
core_total=$(grep -oE 'tests failed out of [0-9]+' "$log/core.txt" | grep -oE '[0-9]+$' || echo 0)
core_failed=$(grep -oE '[0-9]+ tests failed out of' "$log/core.txt" | grep -oE '^[0-9]+' || echo 1)
core_skipped=$(grep -cE 'Not Run|\*\*\*Skipped|Skipped ' "$log/core.txt" || true)

echo "== ROS tests (gtest, rostest)"
rm -rf "$BINLOOP_WS/build/test_results"
(cd "$BINLOOP_WS" && catkin_make -j"$BINLOOP_JOBS" run_tests) >"$log/ros.txt" 2>&1
grep -E '^\[ *(RUN|OK|FAILED|SKIPPED) *\]|Failure|rostest|FAILURE|ERROR' "$log/ros.txt" | grep -v '^\[ RUN' || true
(cd "$BINLOOP_WS" && catkin_test_results build/test_results) | tee "$log/ros-summary.txt" | tail -5
sum_line=$(grep -E '^Summary:' "$log/ros-summary.txt" || echo "Summary: 0 tests, 1 errors, 0 failures, 0 skipped")
ros_total=$(echo "$sum_line" | grep -oE '[0-9]+ tests' | grep -oE '[0-9]+')
ros_err=$(echo "$sum_line" | grep -oE '[0-9]+ errors' | grep -oE '[0-9]+')
ros_fail=$(echo "$sum_line" | grep -oE '[0-9]+ failures' | grep -oE '[0-9]+')
ros_skip=$(echo "$sum_line" | grep -oE '[0-9]+ skipped' | grep -oE '[0-9]+')
[ "$ros_total" -gt 0 ] || { echo "test: no ROS test results found (see $log/ros.txt)"; ros_err=1; }

failed=$((core_failed + ros_err + ros_fail))
skipped=$((core_skipped + ros_skip))
passed=$((core_total - core_failed - core_skipped + ros_total - ros_err - ros_fail - ros_skip))
echo "core: $((core_total - core_failed - core_skipped)) passed, $core_failed failed, $core_skipped skipped; ros: $((ros_total - ros_err - ros_fail - ros_skip)) passed, $((ros_err + ros_fail)) failed, $ros_skip skipped"
echo "binloop: $passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
