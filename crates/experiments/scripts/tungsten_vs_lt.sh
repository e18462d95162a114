#!/usr/bin/env bash
# lt against Tungsten at equal error on the Cornell box, back to back: for each pair of
# estimators, one render of each at every spp level (same scene, same reference, same threads),
# MSE against the reference, and the efficiency ratio
#   (1 / (MSE · seconds))_lt / (1 / (MSE · seconds))_Tungsten     (> 1: lt reaches an error sooner)
# which, where MSE ∝ 1/time, is Tungsten's time to an MSE over lt's. For sppm against Tungsten's
# progressive photon map (consistent: MSE does not fall as 1/time) the time to reach the MSE of
# lt's renders is interpolated on Tungsten's log-log curve instead, and reported as lt / Tungsten
# time (< 1: lt is faster), as issue 28 states that target.
#
# Tungsten is built outside the repository from its public source (nothing of it is committed):
#   git clone https://github.com/tunabrain/tungsten && cd tungsten && mkdir -p build/release &&
#   cd build/release && cmake -DCMAKE_BUILD_TYPE=Release ../.. && make -j2 tungsten
# (its bundled Embree needs CMake < 4, e.g. `pip install cmake==3.27.9`).
#
#   TUNGSTEN=/path/to/tungsten crates/experiments/scripts/tungsten_vs_lt.sh [--quick] [--out F.md]
#
# Times: lt's are its pass loop (`seconds` in the render's JSON record), Tungsten's its own
# "Render time" line; both exclude scene loading. Images: Tungsten's PFM through oiiotool.
# Environment: LT (default target/release/lt), THREADS (2), WIDTH (256; --quick 128).
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
SCRIPTS="$REPO/crates/experiments/scripts"
TUNGSTEN=${TUNGSTEN:-/work/peers/tungsten/build/release/tungsten}
LT=${LT:-$REPO/target/release/lt}
THREADS=${THREADS:-2}
QUICK=0
OUT=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) QUICK=1 ;;
    --out) OUT="$2"; shift ;;
    *) echo "tungsten_vs_lt.sh: unknown argument '$1' (expected --quick or --out FILE)" >&2; exit 2 ;;
  esac
  shift
done
[ -x "$TUNGSTEN" ] || { echo "tungsten_vs_lt.sh: no Tungsten executable at \$TUNGSTEN ($TUNGSTEN)" >&2; exit 3; }
command -v oiiotool >/dev/null || { echo "tungsten_vs_lt.sh: needs oiiotool (OpenImageIO's CLI)" >&2; exit 3; }
[ -x "$LT" ] || cargo build --release -q -p lt-experiments --bin lt --manifest-path "$REPO/Cargo.toml"
if [ "$QUICK" = 1 ]; then WIDTH=${WIDTH:-128}; LEVELS="4 16"; else WIDTH=${WIDTH:-256}; LEVELS="4 16 64"; fi
SCENE_TOML="$REPO/scenes/cornell-box.toml"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# The scene at WIDTH (square film) for lt, and its Tungsten twin per integrator.
sed "s/^resolution = .*/resolution = [$WIDTH, $WIDTH]/" "$SCENE_TOML" >"$WORK/scene.toml"
REF=$("$LT" reference "$SCENE_TOML" --width "$WIDTH" --threads "$THREADS" --results "$REPO/results" 2>&1 |
  grep -o '[^ ]*\.exr' | tail -1)
[ -f "$REF" ] || { echo "tungsten_vs_lt.sh: no reference for $SCENE_TOML" >&2; exit 1; }

mse() { "$LT" compare "$1" "$2" | awk '$1 == "all" { print $2 }'; }
lt_seconds() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seconds"])' "$1"; }
# Tungsten's "Render time 1s 234ms"-style duration in seconds.
tu_seconds() {
  grep -o 'Render time .*' "$1" | tail -1 | python3 -c '
import re, sys
t = sys.stdin.read()
units = {"d": 86400, "h": 3600, "min": 60, "m": 60, "s": 1, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}
print(sum(float(v) * units[u] for v, u in re.findall(r"([0-9.]+)\s*(ms|us|µs|min|d|h|m|s)\b", t)))'
}

ROWS="$WORK/rows.txt"
: >"$ROWS"
# Tungsten alone at SPP: its seconds and MSE.
tungsten_at() {  # tungsten-integrator spp seed
  local theirs=$1 spp=$2 seed=$3
  (cd "$WORK" && "$TUNGSTEN" -t "$THREADS" --spp "$spp" -s "$seed" -d "$WORK" \
    -e "tu-$theirs-$spp.pfm" -o "tu-$theirs-$spp.png" "$WORK/$theirs.json" >"$WORK/tu-$theirs-$spp.log" 2>&1) ||
    { echo "tungsten_vs_lt.sh: Tungsten $theirs failed; its log:" >&2; tail -5 "$WORK/tu-$theirs-$spp.log" >&2; return 1; }
  oiiotool "$WORK/tu-$theirs-$spp.pfm" -o "$WORK/tu-$theirs-$spp.exr"
  echo "$(tu_seconds "$WORK/tu-$theirs-$spp.log") $(mse "$WORK/tu-$theirs-$spp.exr" "$REF")"
}

run_pair() {  # lt-integrator tungsten-integrator [--set k=v ...] — one line per spp level
  local ours=$1 theirs=$2
  shift 2
  python3 "$SCRIPTS/tungsten_scene.py" "$SCENE_TOML" "$WORK/$theirs.json" --integrator "$theirs" \
    --width "$WIDTH" "$@"
  for spp in $LEVELS; do
    local seed=$((spp + 1))
    "$LT" render "$WORK/scene.toml" -i "$ours" --spp "$spp" --seed "$seed" --threads "$THREADS" \
      --quiet -o "$WORK/lt-$ours-$spp.exr"
    local tu
    tu=$(tungsten_at "$theirs" "$spp" "$seed")
    echo "$ours $theirs $spp $(lt_seconds "$WORK/lt-$ours-$spp.json") $(mse "$WORK/lt-$ours-$spp.exr" "$REF")" \
      "$tu $(cut -d' ' -f1 /proc/loadavg)" | tee -a "$ROWS" >&2
  done
}

run_pair pt path_tracer --set enable_light_sampling=true
run_pair light light_tracer
run_pair bdpt bidirectional_path_tracer
# Tungsten's PPM at our sppm's defaults (results/sppm-tungsten/README.md): photons per pass = the
# pixel count, radius 2 pixel footprints on the back wall, α = 2/3, no k-nearest cap.
run_pair sppm progressive_photon_map --set "photon_count=$((WIDTH * WIDTH))" \
  --set "gather_radius=$(python3 -c "print(0.0225 * 256 / $WIDTH)")" --set alpha=0.6666667 \
  --set "gather_photon_count=$((WIDTH * WIDTH))" || echo "sppm progressive_photon_map failed" >>"$ROWS"
# Tungsten's photon map is cheaper per pass and noisier per pass: two longer renders extend its
# curve so lt's MSEs fall inside it (lt's columns "nan": Tungsten alone).
last=${LEVELS##* }
for spp in $((4 * last)) $((16 * last)); do
  tu=$(tungsten_at progressive_photon_map "$spp" $((spp + 1))) &&
    echo "sppm progressive_photon_map $spp nan nan $tu $(cut -d' ' -f1 /proc/loadavg)" | tee -a "$ROWS" >&2
done

python3 - "$ROWS" "$WIDTH" <<'EOF' >"$WORK/report.md"
import math, statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
width = sys.argv[2]
print(f"Cornell box {width}², 2 threads each, one render per (renderer, spp), back to back; "
      "MSE against lt's reference of this film.\n")
print("| lt | Tungsten | spp | lt s | lt MSE | Tungsten s | Tungsten MSE | load | efficiency lt / Tungsten |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
pairs = {}
for r in rows:
    if len(r) != 8:
        print(f"| {' '.join(r)} | | | | | | | | |")
        continue
    ours, theirs, spp, ls, lm, ts, tm, load = r[0], r[1], int(r[2]), *map(float, r[3:])
    eff = (ts * tm) / (ls * lm) if ls == ls else float("nan")
    pairs.setdefault((ours, theirs), []).append((spp, ls, lm, ts, tm, eff))
    print(f"| {ours} | {theirs} | {spp} | {ls:.3f} | {lm:.3e} | {ts:.3f} | {tm:.3e} | {load:.2f} | {eff:.2f} |")
print("\n| pair | summary |")
print("|---|---|")
for (ours, theirs), v in pairs.items():
    if ours == "sppm":
        # Time for Tungsten to reach each lt MSE, log-log interpolated on its own curve.
        tu = sorted((tm, ts) for _, _, _, ts, tm, _ in v)
        ratios = []
        for _, ls, lm, _, _, _ in v:
            if ls != ls:
                continue
            for (m0, t0), (m1, t1) in zip(tu, tu[1:]):
                if m0 <= lm <= m1 and m0 > 0 and m1 > m0:
                    f = math.log(lm / m0) / math.log(m1 / m0)
                    ratios.append(ls / math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))))
        if ratios:
            print(f"| lt `sppm` / Tungsten `{theirs}`, time to an MSE | "
                  f"{statistics.median(ratios):.2f} [{min(ratios):.2f}, {max(ratios):.2f}] over {len(ratios)} MSEs |")
        else:
            print(f"| lt `sppm` / Tungsten `{theirs}`, time to an MSE | lt's MSEs outside Tungsten's range: "
                  "no interpolation (see the rows) |")
    else:
        e = [x[5] for x in v if x[5] == x[5]]
        print(f"| lt `{ours}` / Tungsten `{theirs}`, efficiency at equal error | "
              f"{statistics.median(e):.2f} [{min(e):.2f}, {max(e):.2f}] over {len(e)} spp levels |")
EOF
if [ -n "$OUT" ]; then cp "$WORK/report.md" "$OUT.tmp.$$" && mv "$OUT.tmp.$$" "$OUT"; fi
cat "$WORK/report.md"
