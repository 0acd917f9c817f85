#!/usr/bin/env bash
# Regression check for changes that must keep the model's results: runs every line of
# scripts/regress/runs.txt with two rtsim binaries and compares the statistics key by key
# (scripts/regress/compare.py: identical values, wall times and memory aside).
# Usage: scripts/regress.sh OLD_RTSIM [NEW_RTSIM] [--rename RULES.json] [--filter REGEX]
#   NEW_RTSIM defaults to build/rtsim; SHARED overrides ../shared/scenes.
# Prints one line per run (same / differs, with the differences) and exits 1 if any run differs.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1; shift
new=build/rtsim
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then new=$1; shift; fi
rename=() filter=.
while [ $# -gt 0 ]; do
  case $1 in
    --rename) rename=(--rename "$2"); shift 2 ;;
    --filter) filter=$2; shift 2 ;;
    *) echo "regress: unknown option $1" >&2; exit 2 ;;
  esac
done
shared=${SHARED:-../shared/scenes}
[ -d "$shared" ] || { echo "regress: $shared not found (set SHARED to the scenes folder)" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
failed=0 n=0
while read -r name args; do
  case $name in ''|'#'*) continue ;; esac
  [[ $name =~ $filter ]] || continue
  args=${args//\{shared\}/$shared}
  n=$((n + 1))
  # shellcheck disable=SC2086  # args is a word list by design
  "$old" $args -q --stats "$out/$name.old.json" >/dev/null 2>"$out/$name.old.err" || { echo "$name: old binary failed: $(tail -1 "$out/$name.old.err")"; failed=1; continue; }
  # shellcheck disable=SC2086
  "$new" $args -q --stats "$out/$name.new.json" >/dev/null 2>"$out/$name.new.err" || { echo "$name: new binary failed: $(tail -1 "$out/$name.new.err")"; failed=1; continue; }
  if result=$(python3 scripts/regress/compare.py "$out/$name.old.json" "$out/$name.new.json" "${rename[@]}"); then
    echo "$name: same (${result%%,*})"
  else
    echo "$name: DIFFERS"; echo "$result" | sed 's/^/  /'; failed=1
  fi
done <scripts/regress/runs.txt
echo "regress: $n runs, $([ $failed = 0 ] && echo "all the same" || echo "some differ")"
exit $failed
