#!/usr/bin/env bash
# The equal-time matrix of issue 12: pt, light, bdpt, sppm, bpm and vcm on the four SmallVCM
# twins (scenes/smallvcm-*.toml, SmallVCM's --report scenes 0-3), each for TIME seconds, scored by
# MSE against a long reference per scene.
#
#   crates/experiments/scripts/vcm_matrix.sh [refs|matrix|radius|compare|all]   (default: all)
#
# Parameters (environment; defaults below): TIME (seconds per render), THREADS, SEED (matrix
# seed), SCALE (resolution factor applied to every scene alike: 1 = the twins' 512², 0.5 = 256²),
# REF_TIME (seconds of an unbiased reference), REF_TIME_VCM (seconds of a consistent reference,
# split over its REF_RUNS runs), REF_RADIUS_PX (its initial merging radius), SMALLVCM_R (the
# supplement's bpm/vcm initial radius as a fraction of the scene diameter), OUT, LT (the binary).
#
# Supplement (stage `radius`, part of `all`): bpm and vcm again for TIME s with SmallVCM's own
# merging radius, 0.003 x the scene's bounding-sphere radius = SMALLVCM_R 0.0015 of its diameter
# (r0 = 0.00665, about half our default 2 pixel footprints here). Its rows are marked and take no
# part in choosing a scene's winner.
#
# References (seed 7777 and up, independent of the matrix's seed 1):
#  - smallvcm-mirror-ball: bdpt, one run of REF_TIME s (unbiased; its stderr.exr is the spread of
#    its passes). The area light can be hit, so every path has a bdpt technique; the mirror ball's
#    caustics need bdpt's light-side strategies.
#  - smallvcm-spheres-background: pt, one run of REF_TIME s (unbiased; every path ends on the
#    environment, which BSDF sampling hits; pt's variance per second is half of bdpt's here).
#  - smallvcm-spheres-point, smallvcm-spheres-sun: a delta light (point, directional) makes the
#    caustics seen in the mirror ball and through the glass ball (L S+ D S+ E) unsamplable for pt
#    and bdpt: no edge of such a path joins two non-delta vertices. The reference is therefore
#    vcm itself, REF_RUNS independent runs of REF_TIME_VCM/REF_RUNS s with the initial radius
#    REF_RADIUS_PX pixel footprints (half the matrix's 2: a quarter of its r², so about a quarter
#    of the blur bias at equal passes): consistent, not unbiased; its stderr.exr is the spread
#    across the runs. compare checks it against the matrix's bdpt outside the balls (per-pixel z²).
#
# Writes OUT/<scene>/<integrator>.{exr,json,png}, OUT/<scene>/ref.{exr,stderr.exr,json,png},
# OUT/load.log (uptime before each render), OUT/commands.txt, OUT/table.md (the tables) and
# OUT/README.md (table.md between OUT/intro.md and OUT/analysis.md, hand-written, when present).
# EXRs stay uncommitted (OUT/.gitignore). PNGs: clamped sRGB like lt's own preview, quantised to
# a 256-colour palette (median cut) to keep them near 200 KB at 512². Needs python3 with numpy
# and OpenEXR.
set -euo pipefail
cd "$(dirname "$0")/../../.."

TIME=${TIME:-30}                 # seconds per matrix render (lt stops after the pass crossing it)
THREADS=${THREADS:-2}
SEED=${SEED:-1}
SCALE=${SCALE:-1}                # resolution factor, the same for every render
REF_TIME=${REF_TIME:-240}        # seconds of an unbiased reference (bdpt, pt)
REF_TIME_VCM=${REF_TIME_VCM:-360}  # seconds of a consistent reference (vcm), over REF_RUNS runs
REF_RUNS=${REF_RUNS:-4}          # runs of a consistent (vcm) reference
REF_RADIUS_PX=${REF_RADIUS_PX:-1}
SMALLVCM_R=${SMALLVCM_R:-0.0015}
REF_SEED=7777
OUT=${OUT:-results/vcm-matrix}
LT=${LT:-./target/release/lt}
SCENES=(smallvcm-spheres-sun smallvcm-mirror-ball smallvcm-spheres-point smallvcm-spheres-background)
INTEGRATORS=(pt light bdpt sppm bpm vcm)
stage=${1:-all}

mkdir -p "$OUT"
[ -f "$OUT/.gitignore" ] || printf '*.exr\nscenes/\n' >"$OUT/.gitignore"

# The scene file a render reads: the twin itself at SCALE 1, else a copy with its resolution scaled.
scene() {
  if [ "$SCALE" = 1 ]; then echo "scenes/$1.toml"; return; fi
  mkdir -p "$OUT/scenes"
  python3 - "scenes/$1.toml" "$SCALE" "$OUT/scenes/$1.toml" <<'EOF'
import re, sys
src, k, dst = sys.argv[1], float(sys.argv[2]), sys.argv[3]
t = open(src).read()
t, n = re.subn(r"resolution = \[(\d+), (\d+)\]",
               lambda m: f"resolution = [{round(int(m[1]) * k)}, {round(int(m[2]) * k)}]", t)
assert n == 1, "one resolution line expected"
open(dst, "w").write(t)
EOF
  echo "$OUT/scenes/$1.toml"
}

# Runs one render, logging the load before it and the command.
render() {   # label, lt render arguments…
  local label=$1
  shift
  echo "$(date -u +%FT%TZ) $label :: $(uptime)" >>"$OUT/load.log"
  echo "$LT render $*" >>"$OUT/commands.txt"
  "$LT" render "$@"
}

refs() {
  for s in "${SCENES[@]}"; do
    mkdir -p "$OUT/$s"
    local f; f=$(scene "$s")
    case "$s" in
      smallvcm-mirror-ball)
        render "$s ref" "$f" -i bdpt --time "$REF_TIME" --seed "$REF_SEED" --threads "$THREADS" \
          --quiet -o "$OUT/$s/ref.exr" ;;
      smallvcm-spheres-background)
        render "$s ref" "$f" -i pt --time "$REF_TIME" --seed "$REF_SEED" --threads "$THREADS" \
          --quiet -o "$OUT/$s/ref.exr" ;;
      *)
        render "$s ref" "$f" -i vcm --radius-px "$REF_RADIUS_PX" --runs "$REF_RUNS" \
          --time "$((REF_TIME_VCM / REF_RUNS))" --seed "$REF_SEED" --threads "$THREADS" --quiet \
          -o "$OUT/$s/ref.exr" ;;
    esac
  done
}

matrix() {
  for s in "${SCENES[@]}"; do
    mkdir -p "$OUT/$s"
    local f; f=$(scene "$s")
    for i in "${INTEGRATORS[@]}"; do
      render "$s $i" "$f" -i "$i" --time "$TIME" --seed "$SEED" --threads "$THREADS" --quiet \
        -o "$OUT/$s/$i.exr"
    done
  done
}

radius() {
  for s in "${SCENES[@]}"; do
    local f; f=$(scene "$s")
    for i in bpm vcm; do
      render "$s $i-smallvcm-r" "$f" -i "$i" --radius-scene "$SMALLVCM_R" --time "$TIME" \
        --seed "$SEED" --threads "$THREADS" --quiet -o "$OUT/$s/$i-smallvcm-r.exr"
    done
  done
}

compare() {
  python3 - "$OUT" "$LT" "$TIME" "$SCALE" "$REF_TIME/$REF_TIME_VCM" "$REF_RUNS" "$REF_RADIUS_PX" \
    "${INTEGRATORS[*]}" "${SCENES[@]}" <<'EOF'
import json, os, re, struct, subprocess, sys, tomllib, zlib
import numpy as np, OpenEXR

out, lt, T, scale, ref_time, ref_runs, ref_rpx, integ = sys.argv[1:9]
integrators, scenes = integ.split(), sys.argv[9:]

def rd(p):
    return np.array(OpenEXR.File(p).channels()["RGB"].pixels, dtype=np.float64)

def srgb(v):
    v = np.clip(v, 0, 1)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)

def median_cut(px, n=256):
    boxes = [px]
    while len(boxes) < n:
        i = max(range(len(boxes)),
                key=lambda k: np.ptp(boxes[k], 0).max() * len(boxes[k]) ** 0.5 if len(boxes[k]) > 1 else -1)
        b = boxes.pop(i)
        b = b[np.argsort(b[:, np.ptp(b, 0).argmax()], kind="stable")]
        boxes += [b[: len(b) // 2], b[len(b) // 2:]]
    return np.array([b.mean(0) for b in boxes])

def write_png(path, lin):   # clamped sRGB (lt's preview), 256-colour palette
    q = np.round(srgb(lin) * 255).astype(np.float32)
    h, w, _ = q.shape
    px = q.reshape(-1, 3)
    pal = median_cut(px[::7].copy())
    idx = np.empty(len(px), np.uint8)
    for s in range(0, len(px), 16384):
        idx[s:s + 16384] = ((px[s:s + 16384, None] - pal[None]) ** 2).sum(-1).argmin(1)
    raw = b"".join(b"\0" + row.tobytes() for row in idx.reshape(h, w))
    ck = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    open(path + ".tmp", "wb").write(
        b"\x89PNG\r\n\x1a\n" + ck(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 3, 0, 0, 0))
        + ck(b"PLTE", np.clip(np.round(pal), 0, 255).astype(np.uint8).tobytes())
        + ck(b"IDAT", zlib.compress(raw, 9)) + ck(b"IEND", b""))
    os.replace(path + ".tmp", path)

def ball_mask(scene_file, h, w):
    """Pixels whose camera ray hits a sphere (the delta-surface balls), grown by 2 px."""
    sc = tomllib.load(open(scene_file, "rb"))
    c = sc["camera"]
    e, t, up = (np.array(c[k], float) for k in ("eye", "target", "up"))
    f = (t - e) / np.linalg.norm(t - e)
    r = np.cross(f, up); r /= np.linalg.norm(r)
    u = np.cross(r, f)
    th = np.tan(np.radians(c["fov"]) / 2)
    tx, ty = (th, th * h / w) if c.get("fov_axis", "x") == "x" else (th * w / h, th)
    yy, xx = np.mgrid[0:h, 0:w] + 0.5
    d = f + ((2 * xx / w - 1) * tx)[..., None] * r + ((1 - 2 * yy / h) * ty)[..., None] * u
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    m = np.zeros((h, w), bool)
    for s in sc["shapes"]:
        if s["type"] == "sphere":
            oc = e - np.array(s["center"])
            b = (d * oc).sum(-1)
            m |= (b * b - (oc @ oc - s["radius"] ** 2) > 0) & (b < 0)
    g = m.copy()
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            g |= np.roll(np.roll(m, dy, 0), dx, 1)
    return g

def lt_compare(a, b):
    o = subprocess.run([lt, "compare", a, b], capture_output=True, text=True, check=True).stdout
    row = next(l.split() for l in o.splitlines() if l.startswith("all "))
    return float(row[1]), float(row[2])

load = {}
for line in open(f"{out}/load.log"):
    m = re.match(r"(\S+) (\S+) (\S+) :: .*load average: ([\d.]+), ([\d.]+), ([\d.]+)", line)
    if m:
        load[(m[2], m[3])] = (m[1], float(m[4]))   # the last render of each label

res, lines, checks = {}, [], []
for s in scenes:
    d = f"{out}/{s}"
    ref, rse = rd(f"{d}/ref.exr"), rd(f"{d}/ref.stderr.exr")
    rj = json.load(open(f"{d}/ref.json"))
    rvar = float((rse ** 2).mean())
    h, w, _ = ref.shape
    sf = f"{out}/scenes/{s}.toml" if scale != "1" else f"scenes/{s}.toml"
    balls = ball_mask(sf, h, w)
    rows = {}
    supp = [i for i in ("bpm-smallvcm-r", "vcm-smallvcm-r") if os.path.exists(f"{d}/{i}.exr")]
    for i in integrators + supp:
        a = rd(f"{d}/{i}.exr")
        j = json.load(open(f"{d}/{i}.json"))
        mse, rel = lt_compare(f"{d}/{i}.exr", f"{d}/ref.exr")
        mse_out = float(((a - ref)[~balls] ** 2).mean())
        rows[i] = dict(mse=mse, rel=rel, sub=mse - rvar, s=j["seconds"], passes=j["spp"],
                       load=load.get((s, i), ("?", float("nan")))[1], mean=a.mean() / ref.mean() - 1,
                       out=mse_out, bad=int((~np.isfinite(a)).sum()), inv=j["invalid_samples"])
        write_png(f"{d}/{i}.png", a)
        if i == "bdpt":   # the reference against an independent unbiased render, off the balls
            bse = rd(f"{d}/bdpt.stderr.exr")
            z2 = ((a - ref) ** 2 / (bse ** 2 + rse ** 2 + 1e-30))[~balls]
            diff_on = a[balls].mean() / ref[balls].mean() - 1
            se_on = np.sqrt((bse[balls] ** 2).sum()) / bse[balls].size / ref[balls].mean()
            checks.append((s, float(z2.mean()), float(np.median(z2)), a[~balls].mean() / ref[~balls].mean() - 1,
                           float(np.sqrt((bse[~balls] ** 2).sum()) / bse[~balls].size / ref[~balls].mean()),
                           diff_on, se_on, int(balls.sum())))
    write_png(f"{d}/ref.png", ref)
    res[s] = rows
    win = min(integrators, key=lambda i: rows[i]["mse"])
    src = (f"{rj['integrator']}, {rj['runs']} run(s), {sum(rj['run_passes'])} passes, "
           f"{rj['seconds']:.0f} s, seed {rj['seed']}")
    lines += ["", f"### {s}", "",
              f"Reference: {src}{', --radius-px ' + ref_rpx if rj['integrator'] == 'vcm' else ''}; "
              f"**mean stderr² {rvar:.2e}** ({rj['std_error_source']}); "
              f"{(~balls).sum()} of {h * w} px off the balls.", "",
              "| integrator | passes | s | load (1 min) | MSE | relMSE | MSE − ref. var | MSE × s | "
              "MSE off the balls | mean vs ref | non-finite px / invalid samples |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for i in integrators + supp:
        r = rows[i]
        b = (lambda x: f"**{x}**") if i == win else (lambda x: x)
        m = f"{r['mse']:.3e}"
        name = f"{i[:3]}, SmallVCM's r₀ (supplement)" if i in supp else b(i)
        lines.append(f"| {name} | {r['passes']} | {r['s']:.1f} | {r['load']:.2f} | {b(m)} | "
                     f"{r['rel']:.3e} | {r['sub']:.3e} | {r['mse'] * r['s']:.3e} | {r['out']:.3e} | "
                     f"{r['mean']:+.2%} | {r['bad']} / {r['inv']} |")

lines += ["", "### Combined (MSE, relMSE in brackets; the lowest MSE of each scene in bold)", "",
          "| integrator | " + " | ".join(scenes) + " |", "|---|" + "---:|" * len(scenes)]
for i in integrators:
    cells = []
    for s in scenes:
        r, win = res[s][i], min(integrators, key=lambda k: res[s][k]["mse"])
        m = f"{r['mse']:.3e}"
        cells.append((f"**{m}**" if i == win else m) + f" ({r['rel']:.2e})")
    lines.append(f"| {i} | " + " | ".join(cells) + " |")
for i in ("bpm-smallvcm-r", "vcm-smallvcm-r"):
    if all(i in res[s] for s in scenes):
        lines.append(f"| {i[:3]}, SmallVCM's r₀ (supplement) | "
                     + " | ".join(f"{res[s][i]['mse']:.3e} ({res[s][i]['rel']:.2e})" for s in scenes) + " |")

lines += ["", "### Reference check: the matrix's bdpt against the reference", "",
          "Off the balls every path has a bdpt technique, so bdpt there is unbiased: z² = (bdpt − ref)² /"
          " (stderr²_bdpt + stderr²_ref) per pixel and channel should average about 1 (more where either"
          " standard error is itself noisy: a few passes, or 3 degrees of freedom from 4 runs). On the"
          " balls bdpt misses what the reference has beyond it (the caustics of the delta lights).", "",
          "| scene | mean z² off balls | median z² | bdpt mean off balls vs ref | ± 1σ (bdpt) | bdpt mean on balls vs ref | ± 1σ | ball px |",
          "|---|---:|---:|---:|---:|---:|---:|---:|"]
for c in checks:
    lines.append(f"| {c[0]} | {c[1]:.2f} | {c[2]:.2f} | {c[3]:+.2%} | {c[4]:.2%} | {c[5]:+.2%} | {c[6]:.2%} | {c[7]} |")

g = ["", "| scene | " + " | ".join(integrators) + " | reference |", "|---|" + "---|" * (len(integrators) + 1)]
for s in scenes:
    g.append(f"| {s} | " + " | ".join(f"![{s} {i}]({s}/{i}.png)" for i in integrators)
             + f" | ![{s} reference]({s}/ref.png) |")
if all(os.path.exists(f"{out}/{s}/vcm-smallvcm-r.png") for s in scenes):
    g += ["", "Supplement, SmallVCM's r₀:", "", "| scene | bpm | vcm |", "|---|---|---|"]
    g += [f"| {s} | ![{s} bpm, SmallVCM's r0]({s}/bpm-smallvcm-r.png) | "
          f"![{s} vcm, SmallVCM's r0]({s}/vcm-smallvcm-r.png) |" for s in scenes]
table = "\n".join(lines + ["", "### Images (clamped sRGB, 256-colour palette)"] + g) + "\n"
open(f"{out}/table.md", "w").write(table)

cmds = open(f"{out}/commands.txt").read()
part = lambda n: open(f"{out}/{n}").read() if os.path.exists(f"{out}/{n}") else ""
loads = [float(m[1]) for m in re.finditer(r"load average: ([\d.]+)", open(f"{out}/load.log").read())]
readme = (part("intro.md") + "\n## Results\n" + table + "\n" + part("analysis.md")
          + f"\n## Commands (as run, in order; TIME = {T} s, SCALE = {scale}, REF_TIME/REF_TIME_VCM = {ref_time} s,"
          f" REF_RUNS = {ref_runs}, REF_RADIUS_PX = {ref_rpx})\n\n```sh\n{cmds}```\n"
          f"\n## Machine load\n\n1-minute load average before each render (2 cores, shared):"
          f" min {min(loads):.2f}, median {np.median(loads):.2f}, max {max(loads):.2f};"
          f" every line in [`load.log`](load.log).\n")
open(f"{out}/README.md", "w").write(readme)
print(table)
EOF
}

case "$stage" in
  refs) refs ;;
  matrix) matrix ;;
  radius) radius ;;
  compare) compare ;;
  all) : >"$OUT/load.log"; : >"$OUT/commands.txt"; refs; matrix; radius; compare ;;
  *) echo "usage: $0 [refs|matrix|radius|compare|all]" >&2; exit 2 ;;
esac
