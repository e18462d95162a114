#!/usr/bin/env bash
# lt against pbrt-v4 at equal error, one run: for each pair (lt `pt` / pbrt `path`, `bdpt` /
# `bdpt`, `mmlt` / `mlt`) two independent renders of each renderer at the same samples per pixel
# (mutations per pixel for the Metropolis pair), back to back, on our Cornell box converted by
# pbrt_scene.py (or, with SCENE=…/scene.xml, Bitterli's veach-bidir or a Mitsuba XML scene like
# it, its Beckmann conductors rendered as GGX on both sides). The error is measured without a reference: for independent renders a and b of
# the same estimator, E[mean (a − b)²] = 2 Var, so Var = MSE(a, b) / 2 (`lt compare`'s "all"
# MSE over pixels and RGB). That is the MSE of an unbiased estimator, and of a consistent one up
# to its bias; it needs no common reference, which matters here because pbrt is spectral and
# renders the RGB box 0.7–3.4 % darker per channel (spectral products), a bias that would
# otherwise count against it. Then
#   efficiency ratio = (Var · CPU s)_pbrt / (Var · CPU s)_lt   (> 1: lt better at equal error)
# with CPU s the process's user + system time (scene loading included; the box loads in
# milliseconds in both), the figure to compare on a shared machine.
#
#   PBRT=/path/to/pbrt LT=/path/to/lt crates/experiments/scripts/pbrt_vs_lt.sh [OUT.md]
# pbrt from build_pbrt_v4.sh. Environment: SCENE (scenes/cornell-box.toml), WIDTH (128),
# THREADS (2), SPP_PT (64), SPP_BDPT (16), SPP_MLT (16), SAMPLER (zsobol), WORK (a temporary folder).
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
SCRIPTS="$REPO/crates/experiments/scripts"
PBRT=${PBRT:-$HOME/peers/pbrt-v4/build/pbrt}
LT=${LT:-$REPO/target/release/lt}
WIDTH=${WIDTH:-128}
THREADS=${THREADS:-2}
OUT=${1:-/dev/stdout}
# pbrt's sampler: zsobol (its default, randomised quasi-Monte Carlo) or independent (as lt samples).
SAMPLER=${SAMPLER:-zsobol}
WORK=${WORK:-$(mktemp -d)}
mkdir -p "$WORK"
[ -x "$PBRT" ] || { echo "pbrt_vs_lt.sh: no pbrt at $PBRT (build_pbrt_v4.sh builds one)" >&2; exit 1; }
scene=${SCENE:-$REPO/scenes/cornell-box.toml}
if [[ "$scene" == *.xml ]]; then
  # Mitsuba XML: pbrt_scene.py writes lt's copy ($WORK/lt.xml) beside each pbrt file; the
  # resolution is set by -D on lt's side and by --width on pbrt's.
  lt_scene="$WORK/lt.xml"
  pb_scene="$scene"
  lt_args=(-D integrator=path -D "resx=$WIDTH" -D "resy=$WIDTH")
  pb_args=(--ggx-for-beckmann --lt-xml "$WORK/lt.xml" --width "$WIDTH")
  depth_note="max depth from the scene (pbrt's one less); its Beckmann conductors rendered as GGX by both"
else
  # Our scene at WIDTH: TOML has no -D, so a copy with its resolution replaced.
  sed "s/^resolution = \[256, 256\]/resolution = [$WIDTH, $WIDTH]/" "$scene" >"$WORK/box.toml"
  grep -q "resolution = \[$WIDTH, $WIDTH\]" "$WORK/box.toml" || { echo "pbrt_vs_lt.sh: cannot set the resolution" >&2; exit 1; }
  lt_scene="$WORK/box.toml"
  pb_scene="$WORK/box.toml"
  lt_args=()
  pb_args=()
  depth_note="max depth 8 (pbrt maxdepth 7)"
fi

cpu() { # OUTFILE CMD... → runs CMD, appends its user+sys CPU seconds to OUTFILE
  local f=$1; shift
  /usr/bin/time -f "%U %S" -o "$f.time" "$@" >/dev/null 2>&1 || { echo "pbrt_vs_lt.sh: failed: $*" >&2; exit 1; }
  awk '{ print $1 + $2 }' "$f.time"
}
variance() { # A.exr B.exr → MSE(a, b) / 2
  "$LT" compare "$1" "$2" 2>/dev/null | awk '$1 == "all" { printf "%.6e\n", $2 / 2; exit }'
}

{
  echo "# lt against pbrt-v4, one run"
  echo
  echo "Date: $(date -u '+%Y-%m-%d %H:%M UTC'); lt $(git -C "$REPO" rev-parse --short HEAD); pbrt-v4 $(git -C "$(dirname "$PBRT")/../src" rev-parse --short HEAD 2>/dev/null || echo '?'); load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "Scene: ${scene#$REPO/} at ${WIDTH} px wide, $depth_note, $THREADS threads; pbrt sampler $SAMPLER for path and bdpt (mlt samples its own primary space)."
  echo
  echo "| pair | spp | lt CPU s | pbrt CPU s | lt Var | pbrt Var | time at equal spp, pbrt/lt | **efficiency lt/pbrt** |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|"
} >"$WORK/report.md"

pair() { # LT_INTEGRATOR PBRT_INTEGRATOR SPP [pbrt --set ...]
  local li=$1 pi=$2 spp=$3; shift 3
  local pset=("$@") lt_t=() pb_t=()
  for seed in 1 2; do
    local sppflag=(--spp "$spp")
    [ "$pi" = mlt ] && sppflag=(--spp 1 --set "integer:mutationsperpixel=$spp")
    python3 "$SCRIPTS/pbrt_scene.py" "$pb_scene" "$WORK/pb-$pi.pbrt" --integrator "$pi" \
      "${sppflag[@]}" --sampler "$SAMPLER" --exr "$WORK/pb-$pi-$seed.exr" "${pb_args[@]}" "${pset[@]}"
    lt_t+=("$(cpu "$WORK/lt-$li-$seed" "$LT" render "$lt_scene" "${lt_args[@]}" -i "$li" --spp "$spp" \
      --seed "$seed" --threads "$THREADS" --quiet -o "$WORK/lt-$li-$seed.exr")")
    pb_t+=("$(cpu "$WORK/pb-$pi-$seed" "$PBRT" --nthreads "$THREADS" --seed "$seed" "$WORK/pb-$pi.pbrt")")
  done
  local lv pv
  lv=$(variance "$WORK/lt-$li-1.exr" "$WORK/lt-$li-2.exr")
  pv=$(variance "$WORK/pb-$pi-1.exr" "$WORK/pb-$pi-2.exr")
  python3 - "$li" "$pi" "$spp" "${lt_t[@]}" "${pb_t[@]}" "$lv" "$pv" >>"$WORK/report.md" <<'PY'
import sys
li, pi, spp, l1, l2, p1, p2, lv, pv = sys.argv[1:]
lt, pb, lv, pv = (float(l1) + float(l2)) / 2, (float(p1) + float(p2)) / 2, float(lv), float(pv)
print(f"| lt `{li}` / pbrt `{pi}` | {spp} | {lt:.2f} | {pb:.2f} | {lv:.3e} | {pv:.3e} | {pb / lt:.2f} | **{pv * pb / (lv * lt):.2f}** |")
PY
}

pair pt path "${SPP_PT:-64}"
pair bdpt bdpt "${SPP_BDPT:-16}"
pair mmlt mlt "${SPP_MLT:-16}"
echo >>"$WORK/report.md"
echo "Load at end: $(cut -d' ' -f1-3 /proc/loadavg). CPU s: mean of the two runs. Var: MSE between the two runs / 2. Work files: $WORK" >>"$WORK/report.md"
cat "$WORK/report.md" >"$OUT"
