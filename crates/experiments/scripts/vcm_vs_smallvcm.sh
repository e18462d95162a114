#!/usr/bin/env bash
# Time per iteration of our vcm, bdpt and bpm against SmallVCM's own build on the twin of its
# scene 1 (glossy floor + large mirror ball + ceiling light, 512², path length 10), side by side:
# each round runs SmallVCM's algorithm, then ours, so both see the same machine load.
#
# SmallVCM is built outside the repository from its public source (never committed):
#   git clone https://github.com/SmallVCM/SmallVCM && cd SmallVCM &&
#   g++ -o smallvcm ./src/smallvcm.cxx -O3 -std=c++0x -fopenmp
# Usage: SMALLVCM=/path/to/smallvcm crates/experiments/scripts/vcm_vs_smallvcm.sh [ROUNDS] [ITERS]
#
# Our settings follow SmallVCM's defaults where they are integrator settings: the balance heuristic,
# Russian roulette from the first bounce (--rr-depth 1), one light path per pixel, and its merging
# radius 0.003 × the bounding-sphere radius (= 0.0015 × the diameter, our --radius-scene).
set -euo pipefail
ROUNDS=${1:-3}
ITERS=${2:-8}
SMALLVCM=${SMALLVCM:-/work/peers/smallvcm/smallvcm}
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
LT="$REPO/target/release/lt"
SCENE="$REPO/scenes/smallvcm-mirror-ball.toml"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
[ -x "$LT" ] || cargo build --release -p lt-experiments --manifest-path "$REPO/Cargo.toml"
now() { date +%s.%N; }
printf "%-5s %-5s %10s %10s %8s %6s\n" round algo smallvcm_s ours_s ratio load
for r in $(seq 1 "$ROUNDS"); do
  for pair in "vcm vcm" "bpt bdpt" "bpm bpm"; do
    set -- $pair
    extra=(--mis balance --rr-depth 1)
    [ "$2" != bdpt ] && extra+=(--radius-scene 0.0015)
    t0=$(now)
    (cd "$OUT" && "$SMALLVCM" -s 1 -a "$1" -i "$ITERS" -o "$OUT/$1.hdr" >/dev/null)
    t1=$(now)
    "$LT" render "$SCENE" -i "$2" --spp "$ITERS" "${extra[@]}" --quiet -o "$OUT/$2.exr"
    t2=$(now)
    a=$(echo "$t1 - $t0" | bc -l); b=$(echo "$t2 - $t1" | bc -l)
    printf "%-5s %-5s %10.2f %10.2f %8.3f %6s\n" "$r" "$2" "$a" "$b" "$(echo "$b / $a" | bc -l)" \
      "$(cut -d' ' -f1 /proc/loadavg)"
  done
done
