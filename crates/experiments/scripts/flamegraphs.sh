#!/bin/sh
# A flame graph per integrator (issue 15): perf samples of one render of the Cornell box per
# integrator, drawn as SVG flame graphs with inferno, plus the top self-time functions as text.
#
#   crates/experiments/scripts/flamegraphs.sh [LT] [OUT_DIR]
#
# LT defaults to target/profiling/lt if it exists, else target/release/lt. The best stacks come
# from `cargo build --profile profiling --bin lt` (release code with debug info: perf then shows
# inlined functions as frames of their own). A plain release build has no debug info, but Rust
# keeps .eh_frame, so `--call-graph dwarf` still unwinds it; only the inlined frames are missing
# (their time is charged to the function they were inlined into: in a release build most of
# sppm's photon push and vcm's merging show up as rayon::iter::plumbing::bridge_producer_consumer::helper
# or Engine::merge::{{closure}}). If a binary has no .eh_frame, stacks come out as [unknown]:
# then record without -g/--call-graph and read only the .txt (flat self time).
# OUT_DIR defaults to results/profiles; it gets <integrator>.svg and <integrator>.txt.
#
# Each render: scenes/cornell-box.toml, seed 1, one thread, no checkpoints, a few seconds
# (pt/light 32 spp, bdpt 8, sppm 16, vcm 4). Images and perf data go to a temporary folder.
# Sampling is perf's cpu-clock (a software timer, 2000 Hz), which also works on VMs without
# hardware counters. Shares are what to read; absolute times depend on the machine's load.
#
# Needs perf (linux-perf) and inferno (inferno-collapse-perf, inferno-flamegraph) on PATH or in
# $INFERNO/bin (default /tmp/inferno: `cargo install --root /tmp/inferno inferno`).
# perf needs kernel.perf_event_paranoid <= 2 (profiling one's own processes) or root.
set -e
cd "$(dirname "$0")/../../.."
if [ -n "$1" ]; then
  LT=$1
elif [ -x target/profiling/lt ]; then
  LT=target/profiling/lt
else
  LT=target/release/lt
fi
OUT=${2:-results/profiles}
INFERNO=${INFERNO:-/tmp/inferno}
PATH=$INFERNO/bin:$PATH
for tool in perf inferno-collapse-perf inferno-flamegraph; do
  command -v "$tool" >/dev/null || { echo "flamegraphs.sh: $tool not found" >&2; exit 1; }
done
[ -x "$LT" ] || { echo "flamegraphs.sh: no lt binary at $LT" >&2; exit 1; }
mkdir -p "$OUT"
TMP=$(mktemp -d /tmp/lt-flamegraphs.XXXXXX)
trap 'rm -rf "$TMP"' EXIT

for x in "pt 32" "light 32" "bdpt 8" "sppm 16" "vcm 4"; do
  set -- $x
  i=$1 spp=$2
  echo "== $i ($spp spp)" >&2
  perf record -q -e cpu-clock -F 2000 -g --call-graph dwarf -o "$TMP/$i.data" -- \
    "$LT" render scenes/cornell-box.toml -i "$i" --spp "$spp" --seed 1 --threads 1 \
    --checkpoint 100000 --quiet -o "$TMP/$i.exr" > "$TMP/$i.log" 2>&1
  perf script -i "$TMP/$i.data" 2>/dev/null > "$TMP/$i.perf"
  inferno-collapse-perf --all "$TMP/$i.perf" > "$TMP/$i.folded"
  # --minwidth (pixels) drops frames too narrow to see; 0.1 keeps each SVG well under 1 MB.
  inferno-flamegraph --minwidth 0.1 --countname ns \
    --title "lt $i, cornell-box, $spp spp, 1 thread, seed 1 (perf cpu-clock, 2000 Hz)" \
    < "$TMP/$i.folded" > "$OUT/$i.svg"
  {
    echo "lt $i, scenes/cornell-box.toml, $spp spp, seed 1, 1 thread"
    echo "perf record -e cpu-clock -F 2000 --call-graph dwarf; self time (no children) per function,"
    echo "top 15 at >= 1 % of all samples of the process (its OpenEXR writer threads included)."
    echo
    echo "samples: $(grep -c ' cpu-clock:' "$TMP/$i.perf") (0.5 ms each)"
    echo
    echo "  self  function"
    perf report -i "$TMP/$i.data" --no-children --stdio --percent-limit 1 --sort symbol \
      -g none 2>/dev/null |
      sed -n 's/^ *\([0-9.]*%\) *\(\[.\]\) \(.*[^ -]\)[ -]*$/\1 \2 \3/p' |
      sort -rn | head -n 15 | awk '{ printf "%7s  %s\n", $1, substr($0, length($1) + 2) }'
  } > "$OUT/$i.txt"
done
echo "wrote $OUT/{pt,light,bdpt,sppm,vcm}.{svg,txt}" >&2
