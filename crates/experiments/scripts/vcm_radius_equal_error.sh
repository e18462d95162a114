#!/usr/bin/env bash
# Issue 28, lever 3: is vcm's default merging radius worth its merge cost? The merge cost grows
# with the photons each query finds (∝ r²), so a smaller radius is cheaper per pass but noisier;
# only the error reached in a given time decides. For each scene and initial radius (in pixel
# footprints, `radius_px`), independent runs (seeds) of a fixed number of passes, each timed in
# CPU seconds (the render's JSON record) and measured against the scene's reference: the
# inefficiency relMSE × CPU seconds (lower is better) with a 95 % Student-t interval over runs.
#
#   crates/experiments/scripts/vcm_radius_equal_error.sh [--quick] [--out FILE.csv]
#
# Environment: LT (default: target/release/lt, built if absent), THREADS (1: CPU seconds are
# then one core's, and two sweeps or a sweep and other work can share a 2-core machine),
# WIDTH (128), PASSES (32),
# SEEDS (4), RADII ("0.5 1 2 4"), SCENES (cornell-box veach-door caustic-sds
# smallvcm-mirror-ball), INTEGRATORS ("vcm bpm"). References come from `lt reference` (cached
# under results/references, so a second run reuses them), or REF_<scene with - as _>=FILE.exr.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
WIDTH=${WIDTH:-128}
THREADS=${THREADS:-1}
PASSES=${PASSES:-32}
SEEDS=${SEEDS:-4}
RADII=${RADII:-"0.5 1 2 4"}
SCENES=${SCENES:-"cornell-box veach-door caustic-sds smallvcm-mirror-ball"}
INTEGRATORS=${INTEGRATORS:-"vcm bpm"}
# shellcheck source=quick_out_args.sh
. "$REPO/crates/experiments/scripts/quick_out_args.sh"
parse_quick_out vcm_radius_equal_error.sh "$@"
if [ "$QUICK" = 1 ]; then PASSES=4; SEEDS=2; RADII="1 2"; SCENES="cornell-box"; INTEGRATORS="vcm"; fi
LT=${LT:-$REPO/target/release/lt}
[ -x "$LT" ] || cargo build --release -q -p lt-experiments --bin lt --manifest-path "$REPO/Cargo.toml"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# relMSE of A against REF from `lt compare`'s "all" row (its third column).
rel_mse() { "$LT" compare "$1" "$2" | awk '$1 == "all" { print $3 }'; }
# CPU seconds of a render from its JSON record.
cpu_seconds() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["cpu_seconds"])' "$1"; }

CSV="$WORK/out.csv"
echo "scene,integrator,radius_px,passes,runs,cpu_seconds_mean,relmse_mean,inefficiency_mean,inefficiency_lo,inefficiency_hi" >"$CSV"
for scene in $SCENES; do
  # The scene at WIDTH pixels wide, aspect kept.
  src="$REPO/scenes/$scene.toml"
  # REF_<scene, - as _>=FILE.exr takes another reference (e.g. `lt study`'s for that scene).
  override="REF_${scene//-/_}"
  if [ -n "${!override:-}" ]; then
    ref="${!override}"
  else
  ref_json=$("$LT" reference "$src" --width "$WIDTH" --threads "$THREADS" --results "$REPO/results" 2>&1 | tee "$WORK/ref.log" |
    grep -o '[^ ]*\.exr' | tail -1)
  [ -f "$ref_json" ] || { echo "no reference for $scene:"; cat "$WORK/ref.log"; exit 1; } >&2
  ref="$ref_json"
  fi
  awk -v w="$WIDTH" '/^resolution *=/ { gsub(/[^0-9,]/, "", $0); split($0, a, ",");
    printf "resolution = [%d, %d]\n", w, int(a[2] * w / a[1] + 0.5); next } { print }' "$src" \
    >"$WORK/$scene.toml"
  # Relative paths in the scene (meshes, textures) resolve against its own directory.
  cp -r "$REPO/scenes/"*.obj "$REPO/scenes/textures" "$WORK/" 2>/dev/null || true
  for integ in $INTEGRATORS; do
    for r in $RADII; do
      cpus=()
      rels=()
      for seed in $(seq 1 "$SEEDS"); do
        img="$WORK/$scene-$integ-$r-$seed.exr"
        "$LT" render "$WORK/$scene.toml" -i "$integ" --set "radius_px=$r" --spp "$PASSES" \
          --seed "$seed" --threads "$THREADS" --quiet -o "$img"
        c=$(cpu_seconds "${img%.exr}.json")
        m=$(rel_mse "$img" "$ref")
        cpus+=("$c"); rels+=("$m")
      done
      python3 - "$scene" "$integ" "$r" "$PASSES" "${cpus[*]}" "${rels[*]}" >>"$CSV" <<'EOF'
import statistics, sys
from math import sqrt
scene, integ, r, passes = sys.argv[1:5]
cpus, rels = ([float(x) for x in a.split()] for a in sys.argv[5:7])
vals = [c * m for c, m in zip(cpus, rels)]
n = len(vals)
# Student-t 97.5 % quantiles for n - 1 degrees of freedom (n ≤ 9), else the normal's.
t = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306}.get(n - 1, 1.96)
m = statistics.mean(vals)
h = t * statistics.stdev(vals) / sqrt(n) if n > 1 else float("nan")
print(f"{scene},{integ},{r},{passes},{n},{statistics.mean(cpus):.4g},{statistics.mean(rels):.4g},"
      f"{m:.4g},{m - h:.4g},{m + h:.4g}")
EOF
      tail -1 "$CSV" >&2
    done
  done
done
if [ -n "$OUT" ]; then
  cp "$CSV" "$OUT.tmp.$$" && mv "$OUT.tmp.$$" "$OUT"
fi
column -s, -t "$CSV"
