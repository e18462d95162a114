#!/usr/bin/env bash
# Memory of the photon family: peak resident set size (GNU time's "Maximum resident set size") of
#   - `pm` on cornell-box as the photon map grows (photons = 65 536, 262 144, 1 048 576, 4 194 304
#     photon paths; 1 pass, 256²), and
#   - `sppm` on cornell-box as the resolution grows (64², 128², 256², 512²; PASSES passes; the
#     default photons_per_pass = the pixel count, so photons per pass grow with the pixels too),
#     plus two controls at 512² and 64² with photons_per_pass swapped (16 384 and 262 144) to tell
#     the pixels' share from the per-pass photons'.
# Each point is measured REPS times; the table keeps the largest. Straight-line fits
# (least squares) give bytes per photon path / stored photon (pm) and bytes per pixel (sppm).
#
#   crates/experiments/scripts/photon_memory.sh [measure|report|all]     (default: all)
#
# Environment: LT (binary, default ./target/release/lt), OUT (default results/sppm-slides/memory),
# THREADS (default 2), PASSES (sppm passes, default 4), REPS (default 2), TMP (scene copies and
# images, default /tmp/lt-photon-memory).
#
# Writes OUT/pm.tsv, OUT/sppm.tsv (raw measurements), OUT/memory.md (tables and fits) and
# OUT/memory.svg (the plot; drawn by hand, no matplotlib needed). Needs /usr/bin/time (GNU) and
# python3 with numpy.
set -euo pipefail
cd "$(dirname "$0")/../../.."
LT=${LT:-./target/release/lt}
OUT=${OUT:-results/sppm-slides/memory}
THREADS=${THREADS:-2}
PASSES=${PASSES:-4}
REPS=${REPS:-2}
TMP=${TMP:-/tmp/lt-photon-memory}
PHOTONS=(65536 262144 1048576 4194304)
SIDES=(64 128 256 512)
stage=${1:-all}
mkdir -p "$OUT" "$TMP"

# rss_kib LOG: GNU time's peak RSS, KiB.
rss_kib() { awk -F': ' '/Maximum resident set size/{print $2}' "$1"; }
# photons_stored JSON: pm's stored photons (progress facts).
stored() { python3 -c "import json,sys; f=dict(json.load(open(sys.argv[1]))['progress']['facts']); print(f.get('photons_stored','-'))" "$1"; }
secs() { python3 -c "import json,sys; print(round(json.load(open(sys.argv[1]))['seconds'],2))" "$1"; }

measure() {
  echo -e "photon_paths\tphotons_stored\trep\tpeak_rss_kib\tseconds\tload1" >"$OUT/pm.tsv"
  for n in "${PHOTONS[@]}"; do
    for r in $(seq "$REPS"); do
      o="$TMP/pm-$n.exr"
      l=$(cut -d' ' -f1 /proc/loadavg)
      /usr/bin/time -v -o "$TMP/pm-$n.time" "$LT" render scenes/cornell-box.toml -i pm --spp 1 \
        --set "photons=$n" --seed 1 --threads "$THREADS" --quiet -o "$o"
      echo -e "$n\t$(stored "${o%.exr}.json")\t$r\t$(rss_kib "$TMP/pm-$n.time")\t$(secs "${o%.exr}.json")\t$l" >>"$OUT/pm.tsv"
    done
  done
  echo -e "side\tpixels\tphotons_per_pass\trep\tpeak_rss_kib\tseconds\tload1" >"$OUT/sppm.tsv"
  run_sppm() {   # side photons_per_pass(or "default")
    local w=$1 pp=$2 s="$TMP/cornell-box-$1.toml" set=()
    sed -E "s/^resolution = \[256, 256\]/resolution = [$w, $w]/" scenes/cornell-box.toml >"$s"
    grep -q "^resolution = \[$w, $w\]" "$s"
    [ "$pp" != default ] && set=(--set "photons_per_pass=$pp")
    for r in $(seq "$REPS"); do
      o="$TMP/sppm-$w-$pp.exr"
      l=$(cut -d' ' -f1 /proc/loadavg)
      /usr/bin/time -v -o "$TMP/sppm.time" "$LT" render "$s" -i sppm --spp "$PASSES" "${set[@]}" \
        --seed 1 --threads "$THREADS" --quiet -o "$o"
      local ppn=$pp; [ "$pp" = default ] && ppn=$((w * w))
      echo -e "$w\t$((w * w))\t$ppn\t$r\t$(rss_kib "$TMP/sppm.time")\t$(secs "${o%.exr}.json")\t$l" >>"$OUT/sppm.tsv"
    done
  }
  for w in "${SIDES[@]}"; do run_sppm "$w" default; done
  run_sppm 512 16384   # control: 512² pixels, 16 384 photons per pass
  run_sppm 64 262144   # control: 64² pixels, 262 144 photons per pass
}

report() { python3 - "$OUT" "$PASSES" <<'EOF'
import sys, csv, numpy as np
out, passes = sys.argv[1], sys.argv[2]
def rows(name):
    with open(f"{out}/{name}") as f:
        return list(csv.DictReader(f, delimiter="\t"))
def peak(rs, key):
    best = {}
    for r in rs:
        k = key(r)
        best[k] = max(best.get(k, 0), int(r["peak_rss_kib"]))
    return best
pm = rows("pm.tsv"); sp = rows("sppm.tsv")
pmp = peak(pm, lambda r: (int(r["photon_paths"]), int(r["photons_stored"])))
spp = peak(sp, lambda r: (int(r["side"]), int(r["pixels"]), int(r["photons_per_pass"])))
MiB = 1024 * 1024
x = np.array([k[0] for k in sorted(pmp)], float); xs = np.array([k[1] for k in sorted(pmp)], float)
y = np.array([pmp[k] * 1024 for k in sorted(pmp)], float)
a, b = np.polyfit(x, y, 1); as_, bs = np.polyfit(xs, y, 1)
main = sorted(k for k in spp if k[2] == k[1])
px = np.array([k[1] for k in main], float); py = np.array([spp[k] * 1024 for k in main], float)
c, d = np.polyfit(px, py, 1)
L = []
L.append("| photon paths | photons stored | peak RSS (MiB) | fit (MiB) |")
L.append("|---:|---:|---:|---:|")
for k in sorted(pmp):
    L.append(f"| {k[0]:,} | {k[1]:,} | {pmp[k]/1024:.1f} | {(a*k[0]+b)/MiB:.1f} |")
L.append("")
L.append(f"pm fit: **{a:.1f} bytes per photon path** (**{as_:.1f} bytes per stored photon**, "
         f"{xs[-1]/x[-1]:.2f} stored photons per path), intercept {b/MiB:.1f} MiB.")
L.append("")
L.append("| resolution | pixels | photons per pass | peak RSS (MiB) | fit (MiB) |")
L.append("|---|---:|---:|---:|---:|")
for k in sorted(spp, key=lambda k: (k[1], k[2])):
    f = f"{(c*k[1]+d)/MiB:.1f}" if k in main else "(control)"
    L.append(f"| {k[0]}² | {k[1]:,} | {k[2]:,} | {spp[k]/1024:.1f} | {f} |")
L.append("")
L.append(f"sppm fit (photons per pass = pixels): **{c:.0f} bytes per pixel** (pixel and its photon path "
         f"per pass together), intercept {d/MiB:.1f} MiB.")
ks = sorted(spp)
A = np.array([[1.0, k[1], k[2]] for k in ks]); yy = np.array([spp[k] * 1024 for k in ks], float)
(j0, jp, jq), *_ = np.linalg.lstsq(A, yy, rcond=None)
res = yy - A @ np.array([j0, jp, jq])
L.append("")
L.append(f"sppm joint fit over all {len(ks)} points, RSS = a + b·pixels + c·photons_per_pass: "
         f"**b = {jp:.0f} bytes per pixel, c = {jq:.0f} bytes per photon path of a pass**, "
         f"a = {j0/MiB:.1f} MiB (largest residual {abs(res).max()/MiB:.1f} MiB).")
open(f"{out}/memory.md", "w").write("\n".join(L) + "\n")
print("\n".join(L))

# The plot: two panels, peak RSS (MiB) against photon paths (pm) and against pixels (sppm).
W, H, M = 360, 260, 50
def nice(vmax):   # round tick positions below vmax
    step = 10 ** np.floor(np.log10(vmax / 4)); step *= min((m for m in (1, 2, 5, 10) if vmax / (m * step) <= 5))
    return np.arange(0, vmax, step)
def panel(ox, xs_, ys_, fit, xlabel, title, extra=()):
    xmax = xs_.max() * 1.05; ymax = max(ys_.max(), *(e[1] for e in extra)) * 1.1 if extra else ys_.max() * 1.1
    X = lambda v: ox + M + v / xmax * (W - M - 15)
    Y = lambda v: H - M + 10 - v / ymax * (H - M - 25)
    s = [f'<text x="{ox+W/2}" y="16" text-anchor="middle" font-size="13">{title}</text>',
         f'<line x1="{X(0)}" y1="{Y(0)}" x2="{X(xmax)}" y2="{Y(0)}" stroke="black"/>',
         f'<line x1="{X(0)}" y1="{Y(0)}" x2="{X(0)}" y2="{Y(ymax)}" stroke="black"/>',
         f'<text x="{ox+W/2+15}" y="{H-8}" text-anchor="middle" font-size="11">{xlabel}</text>',
         f'<text x="{ox+12}" y="{H/2}" font-size="11" transform="rotate(-90 {ox+12} {H/2})" text-anchor="middle">peak RSS (MiB)</text>']
    for t in nice(xmax):
        lab = f"{t/1e6:g}M" if xmax > 2e6 else f"{t/1e3:g}k"
        s.append(f'<text x="{X(t)}" y="{Y(0)+14}" text-anchor="middle" font-size="10">{lab}</text>')
    for t in nice(ymax):
        s.append(f'<text x="{X(0)-4}" y="{Y(t)+3}" text-anchor="end" font-size="10">{t:.0f}</text>')
    m, q = fit
    s.append(f'<line x1="{X(0)}" y1="{Y(q)}" x2="{X(xmax)}" y2="{Y(m*xmax+q)}" stroke="#c33" stroke-dasharray="4 3"/>')
    for xv, yv in zip(xs_, ys_):
        s.append(f'<circle cx="{X(xv)}" cy="{Y(yv)}" r="3.5" fill="#236"/>')
    for xv, yv in extra:
        s.append(f'<rect x="{X(xv)-3.5}" y="{Y(yv)-3.5}" width="7" height="7" fill="none" stroke="#393"/>')
    return s
ctrl = [(k[1], spp[k] / 1024) for k in spp if k not in main]
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{2*W}" height="{H}" font-family="sans-serif">',
       '<rect width="100%" height="100%" fill="white"/>']
svg += panel(0, x, y / MiB, (a / MiB, b / MiB), "photon paths", f"pm, 1 pass, 256² ({a:.0f} B/path)")
svg += panel(W, px, py / MiB, (c / MiB, d / MiB), "pixels", f"sppm, {passes} passes ({c:.0f} B/px; squares: controls)", ctrl)
svg.append("</svg>")
open(f"{out}/memory.svg", "w").write("\n".join(svg) + "\n")
EOF
}

case "$stage" in
  measure) measure ;;
  report) report ;;
  all) measure; report ;;
  *) echo "usage: $0 [measure|report|all]" >&2; exit 2 ;;
esac
