#!/usr/bin/env bash
# Issue 28's table in one run: lt against every peer built on this machine, back to back, and the
# ratios beside the issue's targets. Run it on an otherwise idle machine (ratios are what carry
# over: the absolute figures vary by ±20 % on a shared one).
#
#   [LT=/path/to/lt] crates/experiments/scripts/bench_peers.sh [--quick] [--out FILE.md]
#
# lt: built with cargo (release) unless LT names a binary to run instead; a private copy is run by
# every peer's comparison. Full run ≈ 15–20 min on 2 busy cores (the first one also renders
# Tungsten's reference, ≈ 4 min, then cached); --quick ≈ 3 min.
#
# Peers, each skipped with a line saying so when absent (nothing of them is committed):
# - Mitsuba 3 (`pip install mitsuba numpy`, done here when `import mitsuba` fails; `llvm_ad_rgb`
#   needs Debian's libllvm 15 or later, `apt-get install libllvm19`, also done here as root when
#   none is found): `path` against `pt` and `ptracer` against `light`, through
#   bench_vs_mitsuba.py (its header says how it times); and with participating media (issue 43),
#   its `volpath` against `pt` on three scenes of Mitsuba's own render-test suite
#   ($SUITE/participating_media, default ../shared/mitsuba-render-tests/tests/scenes beside the
#   repository), in `scalar_rgb` and `llvm_ad_rgb`, at the suite's size (48 x 48) and max depth
#   (6), with time at equal spp and efficiency at equal error against the suite's references.
# - SmallVCM, built from its public source outside the repository:
#     git clone https://github.com/SmallVCM/SmallVCM && cd SmallVCM &&
#     g++ -o smallvcm ./src/smallvcm.cxx -O3 -std=c++0x -fopenmp
#   and SMALLVCM=/path/to/smallvcm (default /work/peers/smallvcm/smallvcm): its vcm, bpt and bpm
#   against our vcm, bdpt and bpm at its settings, time per iteration (vcm_vs_smallvcm.sh).
# - Tungsten, built from its public source outside the repository:
#     git clone https://github.com/tunabrain/tungsten && cd tungsten && mkdir -p build/release &&
#     cd build/release && CC=gcc-12 CXX=g++-12 cmake -DCMAKE_BUILD_TYPE=Release \
#       -DTARGET_ARCHITECTURE=haswell ../.. && nice -n 10 make -j2 tungsten
#   (CMake < 4 for its bundled Embree: `pip install cmake==3.27.9`), at TUNGSTEN (default
#   /work/peers/tungsten/build/release/tungsten): `pt`, `light` and `bdpt` against its
#   path_tracer, light_tracer and bidirectional_path_tracer at equal error (efficiency
#   1/(MSE·time) against an lt `pt` reference, bdpt also time to target MSEs), `sppm` against its
#   progressive_photon_map at our sppm's settings (time to target MSEs), on the Cornell box
#   converted by tungsten_scene.py, through tungsten_vs_lt.sh (its header has the details).
#
# Ratios: lt throughput / peer throughput (> 1: lt is faster); for SmallVCM the time ratio
# lt / SmallVCM (< 1: lt is faster), as the issue states its target; for Tungsten efficiency
# lt / Tungsten (> 1: lt better) and time to an MSE lt / Tungsten (< 1: lt faster).
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
SCRIPTS="$REPO/crates/experiments/scripts"
# shellcheck source=quick_out_args.sh
. "$SCRIPTS/quick_out_args.sh"
parse_quick_out bench_peers.sh "$@"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
t_start=$(date +%s)
# lt: LT=/path/to/lt runs that binary (no build); otherwise cargo builds it. Either way a private
# copy is run, so a rebuild in the tree cannot change it mid-run.
if [ -n "${LT:-}" ]; then
  [ -x "$LT" ] || { echo "bench_peers.sh: LT=$LT is not an executable" >&2; exit 2; }
  cp "$LT" "$WORK/lt"
  LT_FROM="the binary LT=$LT (sha256 $(sha256sum "$LT" | cut -c1-12)), not built from this tree"
else
  cargo build --release -q -p lt-experiments --bin lt --manifest-path "$REPO/Cargo.toml"
  cp "$REPO/target/release/lt" "$WORK/lt"
  LT_FROM="built from this tree (cargo build --release)"
fi
LT="$WORK/lt"

REPORT="$WORK/report.md"
{
  echo "# lt against its peers, one run"
  echo
  echo "Date: $(date -u '+%Y-%m-%d %H:%M UTC'); repo $(git -C "$REPO" rev-parse --short HEAD)" \
    "; machine: $(nproc) hardware threads; load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo
  echo "lt: $LT_FROM"
  echo
  echo "| pair | ratio (median [min, max] over rounds) | target (issue) |"
  echo "|---|---|---|"
} >"$REPORT"

# Mitsuba 3 from PyPI when absent; Dr.Jit's LLVM backend wants libLLVM ≥ 15 (Debian's libllvm19).
if ! python3 -c "import mitsuba, numpy" 2>/dev/null; then
  echo "bench_peers.sh: installing Mitsuba 3 (pip install mitsuba numpy)" >&2
  python3 -m pip install --quiet mitsuba numpy >&2 || echo "bench_peers.sh: pip install mitsuba failed" >&2
fi
have_llvm=0
for f in /usr/lib/x86_64-linux-gnu/libLLVM-1[5-9]*.so* /usr/lib/x86_64-linux-gnu/libLLVM-[2-9][0-9]*.so* \
  /usr/lib/llvm-1[5-9]/lib/libLLVM* /usr/lib/llvm-[2-9][0-9]/lib/libLLVM*; do
  [ -e "$f" ] && have_llvm=1
done
if [ "$have_llvm" = 0 ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "bench_peers.sh: installing libllvm19 for Mitsuba's llvm_ad_rgb" >&2
  { apt-get install -y -q libllvm19 || { apt-get update -q && apt-get install -y -q libllvm19; }; } >/dev/null 2>&1 ||
    echo "bench_peers.sh: apt-get install libllvm19 failed (llvm_ad_rgb will not load)" >&2
fi
# "### SCENE: Mitsuba VARIANT `peer` vs lt `ours`, …" then a table ending in the median row: one
# row per (scene, variant, pair) with the issue's target: the wall-time ratio, the CPU-time ratio
# and, where the scene had a reference, the efficiency at equal error (columns found by header).
mitsuba_rows() { # FILE.md TARGET
  awk -v target="$2" '
    function cell(i,   v) { v = c[i]; gsub(/^ +| +$/, "", v); return v }
    /^### / { split($0, a, "`"); scene = $2; sub(":", "", scene); variant = $4
      pair = "lt `" a[4] "` / Mitsuba " variant " `" a[2] "` (" scene ")" }
    /^\| round/ { n = split($0, c, "|"); wall = cpu = eff = 0
      for (i = 1; i <= n; i++) { h = cell(i)
        if (h == "**lt/Mitsuba**") wall = i; if (h ~ /by CPU time/) cpu = i; if (h ~ /efficiency/) eff = i } }
    /^\| \*\*median/ { n = split($0, c, "|"); r = cell(wall)
      if (cpu) r = r " wall; " cell(cpu) " CPU time"
      if (eff && cell(eff) != "") r = r "; " cell(eff) " efficiency at equal error"
      print "| " pair " | " r " | " target " |" }
  ' "$1"
}
if python3 -c "import mitsuba" 2>/dev/null; then
  mi_args=(--lt "$LT" --threads 2 --variants llvm_ad_rgb --out "$WORK/mitsuba.md" --work "$WORK/mi")
  if [ "$QUICK" = 1 ]; then mi_args+=(--quick); else mi_args+=(--spp 64 --rounds 5); fi
  python3 "$SCRIPTS/bench_vs_mitsuba.py" "${mi_args[@]}" >"$WORK/mitsuba.log" 2>&1 || {
    echo "bench_peers.sh: bench_vs_mitsuba.py failed; its log:" >&2
    tail -20 "$WORK/mitsuba.log" >&2
    exit 1
  }
  mitsuba_rows "$WORK/mitsuba.md" "≥ 1.0" >>"$REPORT"
  # Participating media (issue 43): volpath against pt on three suite scenes, both variants.
  SUITE=${SUITE:-$REPO/../shared/mitsuba-render-tests/tests/scenes}
  media="$SUITE/participating_media"
  media_scenes=(test_homo_null_envmap_volpath test_hetero_sigmat_volpath test_homo_area_light_volpath)
  if [ -d "$media" ]; then
    md_args=(--lt "$LT" --threads 2 --variants scalar_rgb llvm_ad_rgb --pairs volpath:pt --max-depth 6
      --out "$WORK/mitsuba-media.md" --work "$WORK/mi-media" --scenes)
    for s in "${media_scenes[@]}"; do md_args+=("$media/$s.xml"); done
    if [ "$QUICK" = 1 ]; then md_args+=(--quick); else md_args+=(--spp 256 --rounds 3); fi
    python3 "$SCRIPTS/bench_vs_mitsuba.py" "${md_args[@]}" >"$WORK/mitsuba-media.log" 2>&1 || {
      echo "bench_peers.sh: bench_vs_mitsuba.py (media) failed; its log:" >&2
      tail -20 "$WORK/mitsuba-media.log" >&2
      exit 1
    }
    mitsuba_rows "$WORK/mitsuba-media.md" "≥ 1.0 scalar (issue 43)" >>"$REPORT"
  else
    echo "| Mitsuba 3 \`volpath\` (media) | not run: no suite at \$SUITE ($SUITE) | ≥ 1.0 scalar (issue 43) |" >>"$REPORT"
  fi
else
  echo "| Mitsuba 3 | not run: \`import mitsuba\` fails (pip install mitsuba numpy) | |" >>"$REPORT"
fi

# SmallVCM: median over rounds of lt seconds / SmallVCM seconds, per algorithm.
SMALLVCM=${SMALLVCM:-/work/peers/smallvcm/smallvcm}
if [ -x "$SMALLVCM" ]; then
  if [ "$QUICK" = 1 ]; then rounds=1; iters=1; else rounds=3; iters=8; fi
  # vcm_vs_smallvcm.sh runs $REPO/target/release/lt; a copy of it with REPO and LT pointed at
  # this run's binary keeps every peer on the same lt.
  mkdir -p "$WORK/svcm"
  sed -e "s|^REPO=.*|REPO=\"$REPO\"|" -e "s|^LT=.*|LT=\"$LT\"|" "$SCRIPTS/vcm_vs_smallvcm.sh" \
    >"$WORK/svcm/vcm_vs_smallvcm.sh"
  grep -q "^LT=\"$LT\"" "$WORK/svcm/vcm_vs_smallvcm.sh" ||
    { echo "bench_peers.sh: could not point vcm_vs_smallvcm.sh at $LT" >&2; exit 1; }
  SMALLVCM="$SMALLVCM" bash "$WORK/svcm/vcm_vs_smallvcm.sh" "$rounds" "$iters" >"$WORK/smallvcm.txt"
  cp "$WORK/smallvcm.txt" "$WORK/smallvcm.log"
  for algo in vcm bdpt bpm; do
    awk -v a="$algo" '$2 == a { print $5 }' "$WORK/smallvcm.txt" | sort -g | awk -v a="$algo" '
      { v[NR] = $1 } END {
        if (NR == 0) exit; m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2;
        t = (a == "vcm") ? "≤ 0.7" : "—";
        printf "| lt `%s` / SmallVCM time per iteration (its scene 1, its settings) | %.2f [%.2f, %.2f] | %s |\n", a, m, v[1], v[NR], t }' >>"$REPORT"
  done
else
  echo "| SmallVCM | not run: no executable at \$SMALLVCM ($SMALLVCM) | ≤ 0.7 (vcm) |" >>"$REPORT"
fi

# Tungsten: the summary rows of tungsten_vs_lt.sh, with the issue's targets.
TUNGSTEN=${TUNGSTEN:-/work/peers/tungsten/build/release/tungsten}
if [ -x "$TUNGSTEN" ]; then
  tu_args=(--out "$WORK/tungsten.md")
  if [ "$QUICK" = 1 ]; then tu_args+=(--quick); fi
  LT="$LT" TUNGSTEN="$TUNGSTEN" "$SCRIPTS/tungsten_vs_lt.sh" "${tu_args[@]}" >"$WORK/tungsten.log" 2>&1 || {
    echo "bench_peers.sh: tungsten_vs_lt.sh failed; its log:" >&2
    tail -20 "$WORK/tungsten.log" >&2
    exit 1
  }
  # Its summary rows ("| lt `ours` / Tungsten `theirs`, what | ratio |"), with the issue's targets.
  awk -F'|' '/^\| lt `/ {
      t = "—"
      if ($2 ~ /`bdpt`/) t = ($2 ~ /time to/) ? "≤ 0.5 (2× faster)" : "≥ 2"
      if ($2 ~ /`sppm`/) t = "≤ 0.67"
      if ($2 ~ /`pt`/) t = "— (≥ 1 is against Mitsuba)"
      printf "|%s|%s| %s |\n", $2, $3, t }' "$WORK/tungsten.md" >>"$REPORT"
else
  echo "| Tungsten (equal error) | not run: no executable at \$TUNGSTEN ($TUNGSTEN) | bdpt ≥ 2, sppm ≤ 0.67 |" >>"$REPORT"
fi
{
  echo
  echo "Whole run: $(($(date +%s) - t_start)) s; load at end: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo
  echo "Mitsuba ratios are spp/s of lt over spp/s of Mitsuba (> 1: lt faster); SmallVCM ratios are"
  echo "seconds of lt over seconds of SmallVCM (< 1: lt faster); Tungsten's are efficiency at equal"
  echo "error (> 1: lt faster) and, for sppm, time to an MSE (< 1: lt faster). Full tables follow."
  if [ -f "$WORK/mitsuba.md" ]; then echo; echo "## Mitsuba 3, every round"; echo; cat "$WORK/mitsuba.md"; fi
  if [ -f "$WORK/mitsuba-media.md" ]; then
    echo; echo "## Mitsuba 3 with participating media, every round"; echo; cat "$WORK/mitsuba-media.md"
  fi
  if [ -f "$WORK/smallvcm.log" ]; then echo; echo "## SmallVCM, every round"; echo; echo '```'; cat "$WORK/smallvcm.log"; echo '```'; fi
  if [ -f "$WORK/tungsten.md" ]; then echo; echo "## Tungsten, every render"; echo; cat "$WORK/tungsten.md"; fi
} >>"$REPORT"

if [ -n "$OUT" ]; then
  # Atomic: a reader never sees half a report.
  cp "$REPORT" "$OUT.tmp.$$" && mv "$OUT.tmp.$$" "$OUT"
fi
sed -n '1,/^Mitsuba ratios/p' "$REPORT"
