#!/usr/bin/env bash
# Set-up, build and every test: the ROS-free core tests (plain CMake + ctest, including the check that the
# core uses no ROS) and the ROS tests (catkin gtests and rostests). Exits non-zero on any failure and ends
# with one summary line "binloop: N passed, N failed, N skipped".
#   scripts/test.sh              everything
#   scripts/test.sh --no-setup   skip the apt step (packages already installed)
#   scripts/test.sh --sanitize   only the core unit tests, built with AddressSanitizer and
#                                UndefinedBehaviorSanitizer into .build/core-sanitize, then the threaded
#                                pipeline's tests (the stages on their threads, the background global BA,
#                                the queues) with ThreadSanitizer into .build/core-tsan (any report fails)
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
log="$BINLOOP_BUILD/test-logs"
setup=1 sanitize=0
for a in "$@"; do
  case "$a" in
    --no-setup) setup=0 ;;
    --sanitize) sanitize=1 ;;
    *) echo "test: unknown option $a (--no-setup, --sanitize)"; exit 2 ;;
  esac
done

if [ "$setup" = 1 ]; then
  "$BINLOOP_ROOT/scripts/setup.sh" || { echo "test: set-up failed"; exit 1; }
fi

if [ "$sanitize" = 1 ]; then
  san="$BINLOOP_BUILD/core-sanitize"
  flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
  [ -f "$san/CMakeCache.txt" ] || cmake -S "$BINLOOP_ROOT/cmake/core_only" -B "$san" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
  cmake --build "$san" -j "$BINLOOP_JOBS" || { echo "test: sanitize build failed"; echo "binloop: 0 passed, 1 failed"; exit 1; }
  mkdir -p "$log"
  rm -f "$log/sanitize.xml"
  echo "== core tests under ASan + UBSan"
  (cd "$san" && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --output-on-failure -j "$BINLOOP_JOBS" --timeout 2400 --output-junit "$log/sanitize.xml") \
    2>&1 | tee "$log/sanitize.txt" | grep -vE '^ *Start|Test +#[0-9]+: .* Passed' || true
  [ -f "$log/sanitize.xml" ] || echo '<testsuite><testcase name="ctest-did-not-run"><failure/></testcase></testsuite>' >"$log/sanitize.xml"
  read -r p f s < <("$BINLOOP_ROOT/scripts/junit_summary.py" "$log/sanitize.xml")
  echo "== ASan + UBSan: $p passed, $f failed, $s skipped (log $log/sanitize.txt)"

  # ThreadSanitizer on what runs on more than one thread. OpenCV's and Ceres' own pools are not instrumented,
  # so both are kept on the calling thread (OPENCV_FOR_THREADS_NUM=1; Ceres runs single-threaded unless
  # configured); scripts/tsan.supp names what remains outside binloop.
  tsan="$BINLOOP_BUILD/core-tsan"
  tsan_tests="slam_pipeline_test loop_closing_pipeline_test local_mapper_test bounded_queue_test"
  [ -f "$tsan/CMakeCache.txt" ] || cmake -S "$BINLOOP_ROOT/cmake/core_only" -B "$tsan" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS="-fsanitize=thread -fno-omit-frame-pointer" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=thread" >/dev/null
  # shellcheck disable=SC2086
  cmake --build "$tsan" -j "$BINLOOP_JOBS" --target $tsan_tests || { echo "test: tsan build failed"; echo "binloop: $p passed, $((f + 1)) failed"; exit 1; }
  echo "== threaded tests under ThreadSanitizer"
  tp=0 tf=0
  for t in $tsan_tests; do
    filter='*'
    case "$t" in
      slam_pipeline_test) filter='*Threaded*:*Replay*' ;;
      loop_closing_pipeline_test) filter='*Threaded*:*BackgroundGlobalBa*' ;;
    esac
    if (cd "$tsan" && OPENCV_FOR_THREADS_NUM=1 TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$BINLOOP_ROOT/scripts/tsan.supp" \
        "./$t" --gtest_filter="$filter" --gtest_output="xml:$log/tsan-$t.xml") >"$log/tsan-$t.txt" 2>&1; then
      tp=$((tp + 1)); echo "   tsan $t: passed"
    else
      tf=$((tf + 1)); echo "   tsan $t: FAILED (log $log/tsan-$t.txt)"; grep -m 20 -A 12 "WARNING: ThreadSanitizer" "$log/tsan-$t.txt" || tail -20 "$log/tsan-$t.txt"
    fi
  done
  echo "binloop: $((p + tp)) passed, $((f + tf)) failed, $s skipped (ASan/UBSan core tests, TSan threaded test programs)"
  [ "$f" -eq 0 ] && [ "$tf" -eq 0 ]
  exit
fi
echo "== lint"
lint_p=1 lint_f=0
"$BINLOOP_ROOT/scripts/lint.sh" || { lint_p=0 lint_f=1; echo "test: lint FAILED (the tests still run)"; }
"$BINLOOP_ROOT/scripts/build.sh" || { echo "test: build failed"; echo "binloop: 0 passed, 1 failed"; exit 1; }
mkdir -p "$log"

echo "== core tests (no ROS)"
rm -f "$log/core.xml"
(cd "$BINLOOP_CORE_BUILD" && ctest --output-on-failure -j "$BINLOOP_JOBS" --timeout 900 --output-junit "$log/core.xml") \
  2>&1 | tee "$log/core.txt" | grep -vE '^ *Start|Test +#[0-9]+: .* Passed' || true
[ -f "$log/core.xml" ] || echo '<testsuite><testcase name="ctest-did-not-run"><failure/></testcase></testsuite>' >"$log/core.xml"
read -r core_p core_f core_s < <("$BINLOOP_ROOT/scripts/junit_summary.py" "$log/core.xml")

echo "== ROS tests (gtest, rostest)"
rm -rf "$BINLOOP_WS/build/test_results"
# One test at a time: two rostests side by side (make -j2) share the 2 cores with eight SLAM processes and
# the unpaced split graph then tracks differently (a final-pose error of 0.84 m instead of 0.11 was seen).
(cd "$BINLOOP_WS" && catkin_make -j1 run_tests) >"$log/ros.txt" 2>&1
grep -E '^\[ *(FAILED|SKIPPED) *\]|Failure|FAILURE|ERROR' "$log/ros.txt" || true
shopt -s nullglob
ros_xml=("$BINLOOP_WS"/build/test_results/binloop/*.xml)
if [ ${#ros_xml[@]} -eq 0 ]; then
  echo "test: no ROS test results found (see $log/ros.txt)"
  ros_p=0 ros_f=1 ros_s=0
else
  read -r ros_p ros_f ros_s < <("$BINLOOP_ROOT/scripts/junit_summary.py" "${ros_xml[@]}")
fi

failed=$((core_f + ros_f + lint_f))
echo "lint: $([ "$lint_f" -eq 0 ] && echo passed || echo FAILED); core: $core_p passed, $core_f failed, $core_s skipped; ros: $ros_p passed, $ros_f failed, $ros_s skipped (logs in $log)"
echo "binloop: $((core_p + ros_p + lint_p)) passed, $failed failed, $((core_s + ros_s)) skipped"
[ "$failed" -eq 0 ]
