#!/usr/bin/env bash
# clang-tidy over the core (scripts/lint.sh runs it): the checks .clang-tidy names, every warning an error.
#   scripts/tidy.sh false   the core sources changed since the commit in scripts/tidy_baseline (committed or
#                           not), and those that include a header of include/binloop changed since
#   scripts/tidy.sh true    every core source; when all are clean, scripts/tidy_baseline names HEAD
# Without git history (an unpacked copy, a shallow clone without the baseline) it tidies every core source.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
cd "$BINLOOP_ROOT"
whole="${1:-false}"
baseline_file=scripts/tidy_baseline
base=$(sed -n 's/^\([0-9a-f]\{40\}\)$/\1/p' "$baseline_file" 2>/dev/null | head -1)

mapfile -t core < <(find src/core -name '*.cpp' | sort)
if [ "$whole" != true ] && { [ -z "$base" ] || ! git cat-file -e "$base^{commit}" 2>/dev/null; }; then
  echo "tidy: no baseline commit in this copy's history: the whole core"
  whole=true
fi
if [ "$whole" = true ]; then
  files=("${core[@]}")
else
  # Changed since the baseline: committed, staged, in the tree, or new.
  mapfile -t changed < <({ git diff --name-only "$base" -- src/core include/binloop
                           git ls-files --others --exclude-standard -- src/core include/binloop; } | sort -u)
  declare -A pick=() headers=()
  for f in "${changed[@]}"; do
    [ -f "$f" ] || continue
    case "$f" in
      src/core/*.cpp) pick["$f"]=1 ;;
      include/binloop/*.h|src/core/*.h) headers["$f"]=1 ;;
    esac
  done
  includedAs() {  # how sources name headers: by the path below include/, or (src/core's own) by file name
    local h
    for h in "$@"; do
      case "$h" in include/*) echo "\"${h#include/}\"" ;; *) echo "\"$(basename "$h")\"" ;; esac
    done
  }
  # A changed header reaches every source that includes it, directly or through other headers: each round
  # adds the headers that include one already in the set (one grep a round).
  names=$(mktemp)
  while [ "${#headers[@]}" -gt 0 ]; do
    includedAs "${!headers[@]}" >"$names"
    mapfile -t others < <(find include/binloop src/core -name '*.h' | sort |
                          while read -r h; do [ -n "${headers[$h]:-}" ] || echo "$h"; done)
    [ "${#others[@]}" -gt 0 ] || break
    mapfile -t grew < <(grep -lF -f "$names" "${others[@]}")
    [ "${#grew[@]}" -gt 0 ] || break
    for h in "${grew[@]}"; do headers["$h"]=1; done
  done
  if [ "${#headers[@]}" -gt 0 ]; then
    includedAs "${!headers[@]}" >"$names"
    while read -r user; do pick["$user"]=1; done < <(grep -rlF -f "$names" src/core --include='*.cpp')
  fi
  rm -f "$names"
  mapfile -t files < <(printf '%s\n' "${!pick[@]}" | sed '/^$/d' | sort)
fi
if [ "${#files[@]}" -eq 0 ]; then
  echo "tidy: no core source changed since ${base:0:12} (scripts/tidy_baseline)"
  exit 0
fi

"$BINLOOP_ROOT/scripts/build.sh" --configure-core >/dev/null || { echo "tidy: configuring the core failed"; exit 1; }
echo "tidy: ${#files[@]} core sources$([ "$whole" = true ] || echo " changed since ${base:0:12}")"
out=$(mktemp)
printf '%s\n' "${files[@]}" |
  xargs -P "$BINLOOP_JOBS" -n 1 clang-tidy -p "$BINLOOP_CORE_BUILD" --quiet --use-color=false \
    --warnings-as-errors='*' >"$out" 2>&1
rc=$?
grep -E '(warning|error): ' "$out" | sort -u | sed 's/^/tidy: /'
rm -f "$out"
if [ "$rc" -ne 0 ]; then
  echo "tidy: clang-tidy found what .clang-tidy forbids (above)"
  exit 1
fi
if [ "$whole" = true ] && head=$(git rev-parse HEAD 2>/dev/null); then
  if [ -n "$(git status --porcelain -- src/core include/binloop .clang-tidy)" ]; then
    echo "tidy: the whole core is clean, with changes not committed: commit them and run again to move the baseline"
  else
    printf '# The last commit whose whole core clang-tidy found clean (scripts/tidy.sh true writes it).\n%s\n' "$head" \
      >"$baseline_file"
    echo "tidy: the whole core is clean; $baseline_file names $head (commit it)"
  fi
fi
exit 0
