#!/usr/bin/env bash
# Seed slides: pt, light and bdpt at 4 and 32 spp on four scenes of rising difficulty, each
# scored by MSE against a long bdpt reference rendered with an independent seed.
#
#   crates/experiments/scripts/seed_slides.sh [slides|refs|compare|all]     (default: all)
#
# Environment: LT (binary, default ./target/release/lt), OUT (default results/seed-slides),
# REF_TIME (seconds per reference, default 120), REF_TIME_CB (cornell-box reference, default 240),
# THREADS (default 2).
#
# Writes OUT/<scene>/<integrator>-<spp>spp.{exr,png,stderr.exr,json}, OUT/<scene>/ref-bdpt.*,
# OUT/load.log (uptime before each render) and OUT/table.md (the table of README.md).
# Needs python3 with numpy and mitsuba (pip) to read the reference's standard-error EXR.
set -euo pipefail
cd "$(dirname "$0")/../../.."
LT=${LT:-./target/release/lt}
OUT=${OUT:-results/seed-slides}
REF_TIME=${REF_TIME:-120}
REF_TIME_CB=${REF_TIME_CB:-240}
THREADS=${THREADS:-2}
SCENES=(cornell-box cornell-small-light cornell-glass-light veach-door)
INTEGRATORS=(pt light bdpt)
SPPS=(4 32)
REF_SEED=7777   # slides use seed 1; the reference must be independent of them
stage=${1:-all}
mkdir -p "$OUT"

load() { echo "$(date -u +%FT%TZ) $1 :: $(uptime)" >>"$OUT/load.log"; }

slides() {
  for s in "${SCENES[@]}"; do
    mkdir -p "$OUT/$s"
    for i in "${INTEGRATORS[@]}"; do
      for n in "${SPPS[@]}"; do
        load "$s $i $n spp"
        "$LT" render "scenes/$s.toml" -i "$i" --spp "$n" --seed 1 --threads "$THREADS" --quiet \
          -o "$OUT/$s/$i-${n}spp.exr"
      done
    done
  done
}

refs() {
  for s in "${SCENES[@]}"; do
    mkdir -p "$OUT/$s"
    t=$REF_TIME; [ "$s" = cornell-box ] && t=$REF_TIME_CB
    load "$s reference bdpt ${t}s"
    "$LT" render "scenes/$s.toml" -i bdpt --spp 100000 --time "$t" --seed "$REF_SEED" \
      --threads "$THREADS" --quiet -o "$OUT/$s/ref-bdpt.exr"
  done
}

jget() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
mse() { "$LT" compare "$1" "$2" | awk '$1=="all"{print $2}'; }
var() { python3 - "$1" <<'EOF'
import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
a = np.array(mi.Bitmap(sys.argv[1]), dtype=np.float64)[..., :3]
print(f"{(a**2).mean():.4e}")
EOF
}

compare() {
  {
    echo "| scene | reference: bdpt spp (s) | ref. mean stderr² | integrator | spp | MSE | MSE / ref. var | render s | spp/s |"
    echo "|---|---|---:|---|---:|---:|---:|---:|---:|"
    for s in "${SCENES[@]}"; do
      r="$OUT/$s/ref-bdpt"
      rspp=$(jget "$r.json" spp); rsec=$(jget "$r.json" seconds)
      rv=$(var "$r.stderr.exr")
      for i in "${INTEGRATORS[@]}"; do
        for n in "${SPPS[@]}"; do
          f="$OUT/$s/$i-${n}spp"
          m=$(mse "$f.exr" "$r.exr")
          printf '| %s | %s (%.0f) | %s | %s | %s | %s | %.0f | %.3f | %.1f |\n' \
            "$s" "$rspp" "$rsec" "$rv" "$i" "$n" "$m" \
            "$(python3 -c "print($m/$rv)")" "$(jget "$f.json" seconds)" "$(jget "$f.json" spp_per_second)"
        done
      done
    done
  } >"$OUT/table.md"
  cat "$OUT/table.md"
}

case "$stage" in
  slides) slides ;;
  refs) refs ;;
  compare) compare ;;
  all) slides; refs; compare ;;
  *) echo "usage: $0 [slides|refs|compare|all]" >&2; exit 2 ;;
esac
