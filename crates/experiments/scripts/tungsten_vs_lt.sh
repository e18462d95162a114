#!/usr/bin/env bash
# lt against Tungsten at equal error on the Cornell box (scenes/cornell-box.toml, max depth 8),
# back to back: for each pair of estimators and each spp level, one render of lt then one of
# Tungsten (same scene, same threads, same reference), the MSE of each against the reference
# minus the reference's own variance, and
#   efficiency ratio = (1 / (MSE · seconds))_lt / (1 / (MSE · seconds))_Tungsten   (> 1: lt better)
# which, where MSE ∝ 1/time, is Tungsten's time to an MSE over lt's. For bdpt and for sppm against
# Tungsten's progressive photon map (consistent: its MSE does not fall as 1/time) the time to
# reach target MSEs is interpolated on each renderer's log-log (MSE, seconds) curve across the
# levels, and reported as lt / Tungsten time (< 1: lt is faster), as issue 28 states the targets.
#
# Pairs: lt `pt` / Tungsten `path_tracer` (light sampling on), `light` / `light_tracer`, `bdpt` /
# `bidirectional_path_tracer`, `sppm` / `progressive_photon_map` at our sppm's defaults
# (results/sppm-tungsten/README.md: photon paths per pass = pixel count (65536 at 256²), radius
# 0.0225 at 256² (2 pixel footprints on the back wall, scaled with 256 / WIDTH), α = 2/3,
# gather_photon_count = photons per pass (no k-nearest cap), max_bounces 8; one Tungsten spp = one
# photon pass). Levels (spp or passes): full pt/light/bdpt 4 16 64, sppm 16 64 256 at 256²;
# --quick: 4 16 and 4 16 64 at 128².
#
# Reference: an lt `pt` render of the same film, REF_SPP spp (full 2048 at 256², 232 s on 2 busy
# cores at nice 10, v ≈ 1.6e-5; --quick 2048 at 128², ≈ 20 s), seed 1, cached in CACHE (default
# ${XDG_CACHE_HOME:-~/.cache}/lt-bench-peers, outside the repository) under the scene's hash, the
# width and the spp, so later runs reuse it. Its variance (mean over pixels and RGB of its
# standard-error image squared) is subtracted from every MSE: both renderers are measured against
# the same noisy reference, and without it ratios are pulled towards 1.
#
# Tungsten is built outside the repository from its public source (nothing of it is committed):
#   git clone https://github.com/tunabrain/tungsten && cd tungsten && mkdir -p build/release &&
#   cd build/release && CC=gcc-12 CXX=g++-12 cmake -DCMAKE_BUILD_TYPE=Release \
#     -DTARGET_ARCHITECTURE=haswell ../.. && nice -n 10 make -j2 tungsten
# (its bundled Embree needs CMake < 4, e.g. `pip install cmake==3.27.9`; builds with gcc 12 at
# 88ea020, warnings only). Its example scenes are git-LFS objects; a checkout without them
# (`git checkout HEAD -- CMakeLists.txt cmake src`) is enough.
# One local fix is needed (made in the Tungsten checkout, never committed here): with 2 threads
# its progressive photon map crashes now and then (SIGSEGV in PhotonMapIntegrator::tracePhotons,
# 2 of 3 runs of 64 passes at 128²). startRender enqueues the pass on the thread pool and only
# then stores the task group in _group, which waitForCompletion resets after every pass; a worker
# that starts the pass before the store reads an empty _group in its per-photon abort check
# (`_group->isAborting()` in tracePhotons and tracePixels). The fix: test that _group is set
# before asking it (`_group && _group->isAborting()`) at those two places in
# src/core/integrators/photon_map/PhotonMapIntegrator.cpp; 10 of 10 runs then finish. Without it
# the sppm row reads "not run: Tungsten failed at …".
#
#   TUNGSTEN=/path/to/tungsten LT=/path/to/lt \
#     crates/experiments/scripts/tungsten_vs_lt.sh [--quick] [--out F.md]
#
# Times: lt's are its pass loop (`seconds` in the render's JSON record), Tungsten's its own
# "Render time" log line (the render loop after the scene is built); both exclude scene loading.
# Images: Tungsten's PFM through oiiotool. Environment: LT (default target/release/lt, built with
# cargo if absent), TUNGSTEN, THREADS (2), WIDTH (256; --quick 128), REF_SPP, CACHE.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
SCRIPTS="$REPO/crates/experiments/scripts"
TUNGSTEN=${TUNGSTEN:-/work/peers/tungsten/build/release/tungsten}
LT=${LT:-$REPO/target/release/lt}
THREADS=${THREADS:-2}
CACHE=${CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/lt-bench-peers}
# shellcheck source=quick_out_args.sh
. "$SCRIPTS/quick_out_args.sh"
parse_quick_out tungsten_vs_lt.sh "$@"
[ -x "$TUNGSTEN" ] || { echo "tungsten_vs_lt.sh: no Tungsten executable at \$TUNGSTEN ($TUNGSTEN)" >&2; exit 3; }
command -v oiiotool >/dev/null || { echo "tungsten_vs_lt.sh: needs oiiotool (apt-get install openimageio-tools)" >&2; exit 3; }
[ -x "$LT" ] || cargo build --release -q -p lt-experiments --bin lt --manifest-path "$REPO/Cargo.toml"
if [ "$QUICK" = 1 ]; then
  WIDTH=${WIDTH:-128}; REF_SPP=${REF_SPP:-2048}; LEVELS="4 16"; SPPM_LEVELS="4 16 64"
else
  WIDTH=${WIDTH:-256}; REF_SPP=${REF_SPP:-2048}; LEVELS="4 16 64"; SPPM_LEVELS="16 64 256"
fi
SCENE_TOML="$REPO/scenes/cornell-box.toml"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
t_start=$(date +%s)

# The scene at WIDTH (square film) for lt; its Tungsten twin per integrator (tungsten_scene.py).
sed "s/^resolution = .*/resolution = [$WIDTH, $WIDTH]/" "$SCENE_TOML" >"$WORK/scene.toml"

# Mean over R, G, B of oiiotool's per-channel average of an image (after OPS, e.g. a squaring).
img_mean() {  # image [oiiotool ops...]
  local img=$1
  shift
  oiiotool "$img" "$@" --printstats | awk '/Stats Avg:/ { print ($3 + $4 + $5) / 3; exit }'
}

# The reference: lt pt at REF_SPP, cached.
key=$(sha256sum "$SCENE_TOML" | cut -c1-12)
REF_DIR="$CACHE/cornell-box-$key-pt-${WIDTH}px-${REF_SPP}spp"
REF="$REF_DIR/ref.exr"
if [ ! -f "$REF" ] || [ ! -f "$REF_DIR/ref.stderr.exr" ]; then
  mkdir -p "$REF_DIR"
  echo "tungsten_vs_lt.sh: rendering the reference (lt pt, $REF_SPP spp at ${WIDTH}², once) into $REF_DIR" >&2
  "$LT" render "$WORK/scene.toml" -i pt --spp "$REF_SPP" --seed 1 --threads "$THREADS" --quiet \
    -o "$REF_DIR/ref-tmp.exr"
  for f in "$REF_DIR"/ref-tmp.*; do mv "$f" "${f/ref-tmp/ref}"; done
fi
REF_SECONDS=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seconds"])' "$REF_DIR/ref.json")
REF_VAR=$(img_mean "$REF_DIR/ref.stderr.exr" "$REF_DIR/ref.stderr.exr" --mul)
REF_MEAN=$(img_mean "$REF")

mse() { "$LT" compare "$1" "$2" | awk '$1 == "all" { print $2 }'; }
lt_seconds() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seconds"])' "$1"; }
# Tungsten's "Render time 1m 2s 345ms" (or "0.123s") in seconds.
tu_seconds() {
  grep -o 'Render time .*' "$1" | tail -1 | python3 -c '
import re, sys
t = sys.stdin.read()
units = {"d": 86400, "h": 3600, "m": 60, "s": 1, "ms": 1e-3}
print(sum(float(v) * units[u] for v, u in re.findall(r"([0-9.e+-]+)(ms|d|h|m|s)\b", t)))'
}

ROWS="$WORK/rows.txt"
: >"$ROWS"
# One Tungsten render: prints "seconds MSE mean".
tungsten_at() {  # tungsten-integrator spp seed
  local theirs=$1 spp=$2 seed=$3 base
  base="$WORK/tu-$theirs-$spp"
  (cd "$WORK" && "$TUNGSTEN" -t "$THREADS" --spp "$spp" -s "$seed" -d "$WORK" \
    -e "tu-$theirs-$spp.pfm" -o "tu-$theirs-$spp.png" "$WORK/$theirs.json" >"$base.log" 2>&1) || {
    echo "tungsten_vs_lt.sh: Tungsten $theirs ($spp spp) failed; its log:" >&2
    tail -5 "$base.log" >&2
    return 1
  }
  [ -f "$base.pfm" ] || { echo "tungsten_vs_lt.sh: Tungsten $theirs wrote no image" >&2; return 1; }
  oiiotool "$base.pfm" -o "$base.exr"
  echo "$(tu_seconds "$base.log") $(mse "$base.exr" "$REF") $(img_mean "$base.exr")"
}

run_pair() {  # lt-integrator tungsten-integrator "levels" [tungsten_scene.py --set k=v ...]
  local ours=$1 theirs=$2 levels=$3 spp seed tu load
  shift 3
  python3 "$SCRIPTS/tungsten_scene.py" "$SCENE_TOML" "$WORK/$theirs.json" --integrator "$theirs" \
    --width "$WIDTH" "$@"
  for spp in $levels; do
    seed=$((spp + 11))
    load=$(cut -d' ' -f1 /proc/loadavg)
    "$LT" render "$WORK/scene.toml" -i "$ours" --spp "$spp" --seed "$seed" --threads "$THREADS" \
      --quiet -o "$WORK/lt-$ours-$spp.exr"
    if ! tu=$(tungsten_at "$theirs" "$spp" "$seed"); then
      echo "$ours $theirs $spp failed" >>"$ROWS"
      return 0
    fi
    echo "$ours $theirs $spp $(lt_seconds "$WORK/lt-$ours-$spp.json") $(mse "$WORK/lt-$ours-$spp.exr" "$REF")" \
      "$(img_mean "$WORK/lt-$ours-$spp.exr") $tu $load" | tee -a "$ROWS" >&2
  done
}

run_pair pt path_tracer "$LEVELS" --set enable_light_sampling=true
run_pair light light_tracer "$LEVELS"
run_pair bdpt bidirectional_path_tracer "$LEVELS"
photons=$((WIDTH * WIDTH))
run_pair sppm progressive_photon_map "$SPPM_LEVELS" --set "photon_count=$photons" \
  --set "gather_radius=$(python3 -c "print(0.0225 * 256 / $WIDTH)")" --set alpha=0.6666667 \
  --set "gather_photon_count=$photons"
elapsed=$(($(date +%s) - t_start))

python3 - "$ROWS" "$WIDTH" "$REF_SPP" "$REF_SECONDS" "$REF_VAR" "$REF_MEAN" "$elapsed" "$QUICK" \
  <<'EOF' >"$WORK/report.md"
import math, statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
width, ref_spp = sys.argv[2], sys.argv[3]
ref_s, v, ref_mean, elapsed = map(float, sys.argv[4:8])
quick = sys.argv[8] == "1"
print(f"Cornell box (scenes/cornell-box.toml) at {width}², max depth 8, 2 threads each; for every "
      "(pair, level) one lt render then one Tungsten render, back to back. Reference: lt `pt`, "
      f"{ref_spp} spp, seed 1 ({ref_s:.0f} s when rendered); its variance v = {v:.2e} is subtracted "
      f"from every MSE (MSE* = MSE − v). This part took {elapsed:.0f} s"
      f"{' (--quick)' if quick else ''}.\n")
print("| lt | Tungsten | spp | lt s | lt MSE* | lt mean / ref | Tungsten s | Tungsten MSE* "
      "| Tungsten mean / ref | load | efficiency lt / Tungsten |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
pairs, failed = {}, {}
for r in rows:
    if len(r) != 10:
        failed[(r[0], r[1])] = " ".join(r[2:])
        print(f"| {r[0]} | {r[1]} | {r[2]} | {' '.join(r[3:])} | | | | | | | |")
        continue
    ours, theirs, spp = r[0], r[1], int(r[2])
    ls, lm, lmean, ts, tm, tmean, load = map(float, r[3:])
    lm, tm = lm - v, tm - v
    eff = (ts * tm) / (ls * lm) if lm > 0 and tm > 0 else float("nan")
    pairs.setdefault((ours, theirs), []).append((spp, ls, lm, ts, tm))
    print(f"| {ours} | {theirs} | {spp} | {ls:.3f} | {lm:.3e} | {lmean / ref_mean:.4f} | {ts:.3f} | "
          f"{tm:.3e} | {tmean / ref_mean:.4f} | {load:.2f} | {eff:.2f} |")


def time_to(curve, m):
    """Seconds to reach MSE m on a (MSE, seconds) curve, log-log interpolated; None outside."""
    c = sorted((mm, s) for mm, s in curve if mm > 0)
    for (m0, t0), (m1, t1) in zip(c, c[1:]):
        if m0 <= m <= m1 and m1 > m0:
            f = math.log(m / m0) / math.log(m1 / m0)
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    return None


GRID = [3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5]
summary, detail = [], []
for (ours, theirs), pts in pairs.items():
    name = f"lt `{ours}` / Tungsten `{theirs}`"
    effs = [(tu_s * tu_m) / (l_s * l_m) for _, l_s, l_m, tu_s, tu_m in pts if l_m > 0 and tu_m > 0]
    if ours != "sppm" and effs:
        summary.append(f"| {name}, efficiency 1/(MSE·s) at equal spp | **{statistics.median(effs):.2f}** "
                       f"[{min(effs):.2f}, {max(effs):.2f}] over {len(effs)} spp levels |")
    if ours in ("bdpt", "sppm"):
        lt_curve = [(l_m, l_s) for _, l_s, l_m, _, _ in pts]
        tu_curve = [(tu_m, tu_s) for _, _, _, tu_s, tu_m in pts]
        ratios = []
        for m in GRID:
            a, b = time_to(lt_curve, m), time_to(tu_curve, m)
            if a is not None and b is not None:
                ratios.append(a / b)
                detail.append(f"| {ours} / {theirs} | {m:.0e} | {a:.2f} | {b:.2f} | {a / b:.2f} |")
        if ratios:
            summary.append(f"| {name}, time to an MSE | **{statistics.median(ratios):.2f}** "
                           f"[{min(ratios):.2f}, {max(ratios):.2f}] over {len(ratios)} target MSEs |")
        else:
            summary.append(f"| {name}, time to an MSE | no target MSE inside both curves (see the rows) |")
for (ours, theirs), why in failed.items():
    summary.append(f"| lt `{ours}` / Tungsten `{theirs}` | not run: Tungsten failed at {why} |")
print("\nTime to a target MSE* (log-log interpolation between neighbouring levels of the same "
      "renderer; targets on a 1e-3, 3e-4, … grid inside both curves):\n")
print("| pair | target MSE* | lt s | Tungsten s | lt / Tungsten |")
print("|---|---:|---:|---:|---:|")
print("\n".join(detail) if detail else "| (none) | | | | |")
print("\n| pair | summary (median [min, max]) |")
print("|---|---|")
print("\n".join(summary))
EOF
if [ -n "$OUT" ]; then cp "$WORK/report.md" "$OUT.tmp.$$" && mv "$OUT.tmp.$$" "$OUT"; fi
cat "$WORK/report.md"
