#!/usr/bin/env bash
# lint: the conventions docs/testing.md writes down, checked (scripts/test.sh runs it first, so .ci/run does):
#   - every C++ file is formatted as .clang-format says (clang-format --dry-run --Werror);
#   - no function body in src/core is longer than 80 lines, but those scripts/long_functions.txt still names
#     (a ratchet: a name there that is split must come off the list);
#   - the nodelets stay thin: every onInit at most 40 lines, src/nodelets/tracking_nodelet.cpp at most 200;
#   - clang-tidy (the checks .clang-tidy names, every warning an error) on the core's sources changed since
#     the commit in scripts/tidy_baseline, whose whole core was clean, and on the core sources that include a
#     header changed since (the whole core takes about 6 minutes on 2 cores: docs/decisions.md).
# Warnings are errors in the test builds (BINLOOP_WERROR, set by scripts/test.sh).
#   scripts/lint.sh             check
#   scripts/lint.sh --fix       reformat in place first
#   scripts/lint.sh --tidy-all  clang-tidy on the whole core; when it is clean, scripts/tidy_baseline names HEAD
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
fix=false tidy_all=false
case "${1:-}" in
  --fix) fix=true ;;
  --tidy-all) tidy_all=true ;;
  -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  "") ;;
  *) echo "lint: unknown option $1" >&2; exit 2 ;;
esac
for tool in clang-format clang-tidy; do
  command -v "$tool" >/dev/null || { echo "lint: $tool is not installed (scripts/setup.sh installs it)" >&2; exit 1; }
done
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.h')
else  # an unpacked copy: every source but the build folder's
  mapfile -t files < <(find . -path ./.build -prune -o \( -name '*.cpp' -o -name '*.h' \) -print | sed 's|^\./||' | sort)
fi
status=0
if $fix; then clang-format -i "${files[@]}"; fi
if ! clang-format --dry-run --Werror "${files[@]}" 2>/tmp/binloop_lint_format.$$; then
  grep -o '^[^:]*\.\(cpp\|h\)' /tmp/binloop_lint_format.$$ | sort -u | sed 's/^/lint: not formatted: /'
  echo "lint: scripts/lint.sh --fix formats them" >&2
  status=1
fi
rm -f /tmp/binloop_lint_format.$$
if ! /usr/bin/python3 scripts/function_lengths.py 80 scripts/long_functions.txt src/core | sed 's/^/lint: /'; then
  status=1
fi
long_init=$(/usr/bin/python3 scripts/function_lengths.py 40 /dev/null src/nodelets | grep '::onInit()' || true)
if [ -n "$long_init" ]; then
  echo "$long_init" | sed 's/^/lint: a nodelet wires, its onInit at most 40 lines: /'
  status=1
fi
lines=$(wc -l <src/nodelets/tracking_nodelet.cpp)
if [ "$lines" -gt 200 ]; then
  echo "lint: src/nodelets/tracking_nodelet.cpp is $lines lines (at most 200: move logic into the core or an adapter)"
  status=1
fi
scripts/tidy.sh "$tidy_all" || status=1
[ "$status" -eq 0 ] && echo "lint: ${#files[@]} C++ files formatted; function lengths and the nodelets' sizes within bounds"
exit "$status"
