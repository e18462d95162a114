#!/usr/bin/env bash
# SPPM slides: `sppm` after 1, 4, 32, 256 and TOP passes on cornell-box and caustic-sds, beside
# `bdpt` at TOP spp (the seed lecture's last slides), each scored by MSE against a reference.
#
#   crates/experiments/scripts/sppm_slides.sh [slides|refs|compare|all]     (default: all)
#
# Environment: LT (binary, default ./target/release/lt), OUT (default results/sppm-slides),
# TOP (top pass count, default 4096), TOP_CB (top pass count on cornell-box, default 2048: 4096
# there would take the set past ~25 minutes on 2 cores), THREADS (default 2),
# CB_REF (an existing long pt render of cornell-box to copy; default
# /work/peers/ours/cornell-ref-16k.exr; if absent, one is rendered with CB_REF_SPP spp, seed 77),
# CB_REF_SPP (default 16384), SDS_REF_PASSES (default 8192), SDS_REF_RUNS (default 4),
# FONT (a .ttf for the mosaic labels: oiiotool --text has no default font here).
#
# Every pass count is a separate render with seed 1. sppm's pass k draws from the streams of
# (seed, pixel, k) and its radius schedule depends on k alone, so the N-pass image is exactly the
# first N passes of the TOP-pass run (what a checkpoint at pass N would have been).
#
# References: cornell-box — a long `pt` render (unbiased), copied with its .json/.stderr.exr.
# caustic-sds — pt and bdpt cannot render the caustic seen in the mirror, so the reference is
# `sppm` itself, SDS_REF_RUNS independent runs (seeds 7777 + k) of SDS_REF_PASSES passes: consistent,
# not unbiased (its residual bias is that of an SDS_REF_PASSES-pass run), the best available.
#
# Writes OUT/<scene>/sppm-<N>pass.{exr,png,json}, OUT/<scene>/bdpt-<N>spp.{exr,png,stderr.exr,json},
# OUT/<scene>/ref.*, OUT/<scene>/mosaic.png (labelled), OUT/load.log (uptime before each render)
# and OUT/table.md (the tables of README.md).
# Needs python3 with numpy and mitsuba (pip) to read the standard-error EXRs, and oiiotool.
set -euo pipefail
cd "$(dirname "$0")/../../.."
LT=${LT:-./target/release/lt}
OUT=${OUT:-results/sppm-slides}
TOP=${TOP:-4096}
TOP_CB=${TOP_CB:-2048}
THREADS=${THREADS:-2}
CB_REF=${CB_REF:-/work/peers/ours/cornell-ref-16k.exr}
CB_REF_SPP=${CB_REF_SPP:-16384}
SDS_REF_PASSES=${SDS_REF_PASSES:-8192}
SDS_REF_RUNS=${SDS_REF_RUNS:-4}
FONT=${FONT:-/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf}   # oiiotool --text has no default
SCENES=(cornell-box caustic-sds)
REF_SEED=7777   # slides use seed 1; the sppm reference must be independent of them
stage=${1:-all}
mkdir -p "$OUT"

load() { echo "$(date -u +%FT%TZ) $1 :: $(uptime)" >>"$OUT/load.log"; }
top() { if [ "$1" = cornell-box ]; then echo "$TOP_CB"; else echo "$TOP"; fi; }
passes() { echo 1 4 32 256 "$(top "$1")"; }

slides() {
  for s in "${SCENES[@]}"; do
    mkdir -p "$OUT/$s"
    for n in $(passes "$s"); do
      load "$s sppm $n passes"
      "$LT" render "scenes/$s.toml" -i sppm --spp "$n" --seed 1 --threads "$THREADS" --quiet \
        -o "$OUT/$s/sppm-${n}pass.exr"
    done
    n=$(top "$s")
    load "$s bdpt $n spp"
    "$LT" render "scenes/$s.toml" -i bdpt --spp "$n" --seed 1 --threads "$THREADS" --quiet \
      -o "$OUT/$s/bdpt-${n}spp.exr"
  done
}

refs() {
  mkdir -p "$OUT/cornell-box" "$OUT/caustic-sds"
  if [ -f "$CB_REF" ]; then
    b=${CB_REF%.exr}
    load "cornell-box reference: copy of $CB_REF"
    for e in exr stderr.exr png json; do cp "$b.$e" "$OUT/cornell-box/ref.$e"; done
    [ -f "$b.log" ] && cp "$b.log" "$OUT/cornell-box/ref.time.log"
    echo "$CB_REF" >"$OUT/cornell-box/ref.source"
  else
    load "cornell-box reference pt $CB_REF_SPP spp"
    "$LT" render scenes/cornell-box.toml -i pt --spp "$CB_REF_SPP" --seed 77 --threads "$THREADS" \
      --quiet -o "$OUT/cornell-box/ref.exr"
    echo "rendered by $0: pt --spp $CB_REF_SPP --seed 77" >"$OUT/cornell-box/ref.source"
  fi
  load "caustic-sds reference sppm $SDS_REF_RUNS x $SDS_REF_PASSES passes"
  "$LT" render scenes/caustic-sds.toml -i sppm --spp "$SDS_REF_PASSES" --runs "$SDS_REF_RUNS" \
    --seed "$REF_SEED" --threads "$THREADS" --quiet -o "$OUT/caustic-sds/ref.exr"
  echo "rendered by $0: sppm --spp $SDS_REF_PASSES --runs $SDS_REF_RUNS --seed $REF_SEED" \
    >"$OUT/caustic-sds/ref.source"
}

jget() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
mse() { "$LT" compare "$1" "$2" | awk '$1=="all"{print $2, $3}'; }   # MSE, relMSE
# MSE outside the reference's bright pixels (value > 2, grown by 1 px: the lamp, its images in
# delta surfaces and the caustic's core, whose few pixels carry most of the squared error), the
# share of the squared error inside them, their count, and the image mean against the reference's.
extra() { python3 - "$1" "$2" <<'EOF'
import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
a, r = (np.array(mi.Bitmap(f), dtype=np.float64)[..., :3] for f in sys.argv[1:3])
m = r.max(-1) > 2
g = m.copy()
for dy in (-1, 0, 1):
    for dx in (-1, 0, 1):
        g |= np.roll(np.roll(m, dy, 0), dx, 1)
e = ((a - r) ** 2).mean(-1)
print(f"{e[~g].mean():.3e} {e[g].sum() / e.sum():.2f} {int(g.sum())} {a.mean() / r.mean() - 1:+.2%}")
EOF
}
var() { python3 - "$1" <<'EOF'
import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
a = np.array(mi.Bitmap(sys.argv[1]), dtype=np.float64)[..., :3]
print(f"{(a**2).mean():.4e}")
EOF
}
# Last mean radius and the photon paths of a run (sppm's progress record).
prog() { python3 - "$1" <<'EOF'
import json, sys
p = json.load(open(sys.argv[1]))["progress"]
print(f'{p["mean_radius_per_pass"][-1]:.3e} {sum(p["photon_paths_per_pass"])}')
EOF
}

compare() {
  {
    for s in "${SCENES[@]}"; do
      r="$OUT/$s/ref"
      rv=$(var "$r.stderr.exr")
      echo
      echo "### $s ($(cat "$r.source"); reference mean stderr² $rv)"
      echo
      echo "| integrator | passes (spp) | photon paths | last mean radius | render s | MSE (all) | relMSE | MSE / ref. var | MSE outside bright px | bright px share of SE | mean vs ref |"
      echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
      row() {   # integrator passes photon-paths radius file
        local f=$5 m rel x sh bias
        read -r m rel < <(mse "$f.exr" "$r.exr")
        read -r x sh BRIGHT bias < <(extra "$f.exr" "$r.exr")
        printf '| %s | %s | %s | %s | %.2f | %s | %s | %.0f | %s | %s | %s |\n' "$1" "$2" "$3" "$4" \
          "$(jget "$f.json" seconds)" "$m" "$rel" "$(python3 -c "print($m/$rv)")" "$x" "$sh" "$bias"
      }
      for n in $(passes "$s"); do
        f="$OUT/$s/sppm-${n}pass"
        read -r rad ph < <(prog "$f.json")
        row sppm "$n" "$ph" "$rad" "$f"
      done
      n=$(top "$s")
      row bdpt "$n" — — "$OUT/$s/bdpt-${n}spp"
      echo
      echo "Bright pixels (reference > 2 in some channel, grown by 1 px): $BRIGHT."
      # Mosaic: sppm at each pass count, bdpt, reference; labelled.
      args=()
      LABEL="--text:x=4:y=16:size=14:color=1,1,0:font=$FONT"
      for n in $(passes "$s"); do
        args+=("$OUT/$s/sppm-${n}pass.png" "$LABEL" "sppm $n")
      done
      n=$(top "$s")
      args+=("$OUT/$s/bdpt-${n}spp.png" "$LABEL" "bdpt $n spp")
      args+=("$r.png" "$LABEL" "reference")
      oiiotool "${args[@]}" --mosaic:pad=2 7x1 -o "$OUT/$s/mosaic.png"
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
