#!/usr/bin/env python3
"""lt `sppm` against pbrt-v4 `sppm`: time to an MSE (issue 47's target: lt ≤ 1.0× pbrt's time),
one run, on the Cornell box converted by pbrt_scene.py.

    PBRT=/path/to/pbrt LT=/path/to/lt pbrt_sppm_vs_lt.py [--width 128] [--threads 2]
        [--levels 16 64 256] [--ref-spp 1024] [--work DIR] [--out OUT.md]

pbrt is spectral and renders the RGB box a few per cent darker per channel (results/
bench-peers.md), a bias that would swamp sppm's own error against a common reference. So each
renderer is measured against its OWN unbiased reference: lt `pt` and pbrt `path` (independent
sampler), each the mean of two independent runs of REF_SPP spp, whose variance MSE(run 1, run 2)/4
is subtracted from every MSE. Both sppm's are run at the same settings: photon paths per pass =
the pixel count, α = 2/3 (pbrt's is fixed at 2/3), initial radius 2 pixel footprints on the back
wall (lt's default `radius_px` 2; pbrt takes a radius in scene units: 0.0225 · 256 / width, as
tungsten_vs_lt.sh gives Tungsten), max depth 8 (pbrt maxdepth 7). Levels are passes (pbrt:
iterations = spp). Time is each process's user + system CPU seconds (scene loading included; the
box loads in milliseconds). The time to reach a target MSE is interpolated on each renderer's
log–log (CPU s, MSE) curve; the ratio lt / pbrt < 1 means lt gets there first.
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", "..", ".."))


def fail(msg):
    sys.exit(f"pbrt_sppm_vs_lt.py: {msg}")


def cpu_run(cmd):
    """Runs cmd (output discarded) and returns its children's user + system CPU seconds."""
    before = os.times()
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = os.times()
    if r.returncode != 0:
        fail(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr[-2000:]}")
    return (after.children_user - before.children_user) + (after.children_system - before.children_system)


def mse(lt, a, b):
    out = subprocess.run([lt, "compare", a, b], capture_output=True, text=True).stdout
    for line in out.splitlines():
        f = line.split()
        if f and f[0] == "all":
            return float(f[1])
    fail(f"lt compare {a} {b} printed no 'all' row")


def mean_of(a, b, out):
    subprocess.run(["oiiotool", a, "--ch", "R,G,B", b, "--ch", "R,G,B", "--add", "--mulc", "0.5",
                    "-o", out], check=True)


def time_to(curve, target):
    """log-log interpolation of CPU s at MSE = target on [(seconds, mse), ...] (None outside)."""
    pts = sorted(curve)
    for (t0, m0), (t1, m1) in zip(pts, pts[1:]):
        if (m0 - target) * (m1 - target) <= 0 and m0 > 0 and m1 > 0 and m0 != m1:
            u = (math.log(target) - math.log(m0)) / (math.log(m1) - math.log(m0))
            return math.exp(math.log(t0) + u * (math.log(t1) - math.log(t0)))
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--levels", type=int, nargs="+", default=[16, 64, 256])
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--work")
    ap.add_argument("--out", default="/dev/stdout")
    a = ap.parse_args()
    lt = os.environ.get("LT", os.path.join(REPO, "target/release/lt"))
    pbrt = os.environ.get("PBRT", os.path.expanduser("~/peers/pbrt-v4/build/pbrt"))
    for exe in (lt, pbrt):
        if not os.access(exe, os.X_OK):
            fail(f"no executable at {exe}")
    work = a.work or tempfile.mkdtemp(prefix="pbrt-sppm-")
    os.makedirs(work, exist_ok=True)
    w = a.width
    src = open(os.path.join(REPO, "scenes/cornell-box.toml")).read()
    box = os.path.join(work, "box.toml")
    text, n = re.subn(r"^resolution = \[256, 256\]", f"resolution = [{w}, {w}]", src, flags=re.M)
    if n != 1:
        fail("cannot set the box's resolution")
    open(box, "w").write(text)
    radius = 0.0225 * 256 / w
    load0 = open("/proc/loadavg").read().split()[:3]
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())

    def pbrt_file(name, integrator, spp, exr, *extra):
        f = os.path.join(work, name)
        subprocess.run([sys.executable, os.path.join(HERE, "pbrt_scene.py"), box, f, "--integrator",
                        integrator, "--spp", str(spp), "--sampler", "independent", "--exr", exr,
                        *extra], check=True)
        return f

    # References: two independent runs each; their mean, and its variance MSE(r1, r2) / 4.
    refs = {}
    for who in ("lt", "pbrt"):
        runs = []
        for seed in (1, 2):
            exr = os.path.join(work, f"ref-{who}-{seed}.exr")
            if not os.path.exists(exr):
                if who == "lt":
                    cpu_run([lt, "render", box, "-i", "pt", "--spp", str(a.ref_spp), "--seed",
                             str(seed), "--threads", str(a.threads), "--quiet", "-o", exr])
                else:
                    f = pbrt_file(f"ref-{seed}.pbrt", "path", a.ref_spp, exr)
                    cpu_run([pbrt, "--nthreads", str(a.threads), "--seed", str(seed), f])
            runs.append(exr)
        ref = os.path.join(work, f"ref-{who}.exr")
        mean_of(runs[0], runs[1], ref)
        refs[who] = (ref, mse(lt, runs[0], runs[1]) / 4)

    curves = {"lt": [], "pbrt": []}
    rows = []
    for n in a.levels:
        exr = os.path.join(work, f"lt-{n}.exr")
        t_lt = cpu_run([lt, "render", box, "-i", "sppm", "--spp", str(n), "--seed", "1",
                        "--threads", str(a.threads), "--quiet", "-o", exr])
        m_lt = mse(lt, exr, refs["lt"][0]) - refs["lt"][1]
        exr_p = os.path.join(work, f"pbrt-{n}.exr")
        f = pbrt_file(f"sppm-{n}.pbrt", "sppm", n, exr_p, "--set", f"float:radius={radius}")
        t_pb = cpu_run([pbrt, "--nthreads", str(a.threads), "--seed", "1", f])
        m_pb = mse(lt, exr_p, refs["pbrt"][0]) - refs["pbrt"][1]
        curves["lt"].append((t_lt, m_lt))
        curves["pbrt"].append((t_pb, m_pb))
        rows.append(f"| {n} | {t_lt:.2f} | {m_lt:.3e} | {t_pb:.2f} | {m_pb:.3e} |")

    lo = max(min(m for _, m in c) for c in curves.values())
    hi = min(max(m for _, m in c) for c in curves.values())
    targets = [hi, math.sqrt(lo * hi), lo] if lo < hi else []
    out = [
        "# lt `sppm` against pbrt-v4 `sppm`, time to an MSE, one run\n",
        f"Date: {started}; lt {os.path.basename(lt)}; load at start {' '.join(load0)}; "
        f"scenes/cornell-box.toml at {w}², {a.threads} threads; pbrt radius {radius:.4g}, "
        f"photons per pass = pixel count both; references {a.ref_spp} spp × 2 (lt pt, pbrt "
        f"path), their variances {refs['lt'][1]:.2e} (lt) and {refs['pbrt'][1]:.2e} (pbrt) "
        "subtracted.\n",
        "| passes | lt CPU s | lt MSE | pbrt CPU s | pbrt MSE |",
        "|---:|---:|---:|---:|---:|",
        *rows,
        "",
        "| target MSE | lt CPU s | pbrt CPU s | **lt / pbrt time** |",
        "|---:|---:|---:|---:|",
    ]
    for m in targets:
        tl, tp = time_to(curves["lt"], m), time_to(curves["pbrt"], m)
        if tl and tp:
            out.append(f"| {m:.3e} | {tl:.2f} | {tp:.2f} | **{tl / tp:.2f}** |")
    if not targets:
        out.append("| — | the two MSE ranges do not overlap | | |")
    out.append(f"\nLoad at end: {' '.join(open('/proc/loadavg').read().split()[:3])}. Work files: {work}")
    with open(a.out, "w") as fo:
        fo.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
