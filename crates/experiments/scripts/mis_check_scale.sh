#!/usr/bin/env bash
# The scale run behind results/mis-check-scale.md: `lt mis-check` on every shipped TOML scene at
# about 10^6 checked paths for bdpt (power) and 10^5–10^6 for the other integrators/heuristics,
# with the derived per-path tolerance at --slack 1. Prints one markdown row per run:
# scene, integrator, heuristic, paths checked, failures, largest mismatch / tolerance, seconds.
# Usage: [MIS_CHECK_OUT=DIR] crates/experiments/scripts/mis_check_scale.sh [LT_BINARY] > rows.md
# (MIS_CHECK_OUT keeps each run's full table and its failing paths.)
set -uo pipefail
cd "$(dirname "$0")/../../.."
LT=${1:-target/release/lt}
# MIS_CHECK_RUNS="vcm power 10000;bpm power 10000" replaces the list (integrator, heuristic, paths).
RUNS=("bdpt power 60000" "bdpt balance 20000" "pt power 20000" "vcm power 10000" "vcm balance 10000" "bpm power 10000")
if [ -n "${MIS_CHECK_RUNS:-}" ]; then IFS=';' read -r -a RUNS <<< "$MIS_CHECK_RUNS"; fi
# MIS_CHECK_SCENES="scenes/a.toml scenes/b.toml" limits the scenes.
for scene in ${MIS_CHECK_SCENES:-scenes/*.toml}; do
  for run in "${RUNS[@]}"; do
    set -- $run
    start=$(date +%s.%N)
    out=$("$LT" mis-check "$scene" --integrator "$1" --mis "$2" --paths "$3" 2>&1)
    rc=$?
    [ -n "${MIS_CHECK_OUT:-}" ] && echo "$out" > "$MIS_CHECK_OUT/$(basename "$scene" .toml)-$1-$2.txt"
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    # The last column group: rel/tol is the column headed "rel/tol"; take its maximum over lengths.
    worst=$(echo "$out" | awk '
      /rel\/tol/ { for (i = 1; i <= NF; i++) if ($i == "rel/tol") from_right = NF - i; next }
      from_right != "" && $1 ~ /^[0-9]+$/ { v = $(NF - from_right) + 0; if (v > m) m = v }
      END { printf "%.3f", m }')
    summary=$(echo "$out" | grep -E '^(ok|FAIL|fail|error)' | tail -1)
    [ -z "$summary" ] && summary=$(echo "$out" | tail -1)
    printf '| %s | %s | %s | %s | %s | %s | %.0f |\n' "$(basename "$scene" .toml)" "$1" "$2" "$summary" "$rc" "$worst" "$secs"
  done
done
