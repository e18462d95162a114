#!/usr/bin/env python3
"""Throughput of lt against Mitsuba 3 on the same scenes, in one run (issue 15, "Speed").

Full run (about 3-5 minutes on an idle 2-core machine: 2 scenes x 7 rounds x 4 renders of 64 spp
at 256 x 256, a few seconds each, plus Mitsuba's one-off JIT compiles). Run it on an otherwise
idle machine:

    pip install mitsuba numpy                  # Mitsuba 3.x (tested with 3.9.1, Dr.Jit 1.5)
    apt-get install -y libllvm19               # for llvm_ad_rgb (libllvm16/15 work too)
    cargo build --release --bin lt && cp target/release/lt /tmp/lt-bench-binary
    python3 crates/experiments/scripts/bench_vs_mitsuba.py --lt /tmp/lt-bench-binary \
        --spp 64 --rounds 7 --threads 2 --variants llvm_ad_rgb --out results/bench-vs-mitsuba.md

Smoke test (a few seconds of rendering): add --quick (4 spp, 1 round).

Mitsuba XML scenes (issue 43: participating media) are rendered as they are, by both renderers,
with no `lt convert`: e.g. three scenes of Mitsuba's own media suite, `volpath` against lt's `pt`,
both variants, the suite's max depth 6 and its own resolution (48 x 48):

    python3 crates/experiments/scripts/bench_vs_mitsuba.py --lt /tmp/lt-bench-binary \
        --scenes $SUITE/participating_media/test_homo_null_envmap_volpath.xml … \
        --pairs volpath:pt --variants scalar_rgb llvm_ad_rgb --max-depth 6 --spp 256

`-D key=value` sets an XML scene's `$key` for both (e.g. -D res=128). When the scene's folder
holds Mitsuba's reference `refs/<scene without _volpath>_ref_rgb.exr` of the rendered size, each
render's MSE against it is shown too, and the efficiency ratio at equal error,
(MSE_Mitsuba · t_Mitsuba) / (MSE_lt · t_lt) (> 1: lt reaches a given error sooner); MSE* subtracts
the reference's own noise: the mean of its per-sample variance image `_var` over the 32,000
samples per pixel the suite's references were rendered with (its README).

What it does, per scene (default scenes/cornell-box.toml and scenes/bench/cornell-glossy-glass.toml):
`lt convert` writes the scene as Mitsuba XML once; Mitsuba loads it once per variant (in this
process, so the scene and the JIT kernels are reused). Then, per thread count and round, back to
back: Mitsuba `path` against lt `pt`, and Mitsuba `ptracer` against lt `light`, max depth 8,
rr depth 5, at the scene's own resolution and box filter. Light tracing's "spp" is the same in
both: per sample per pixel, one light path per image pixel (lt: --light-paths defaults to the
pixel count; Mitsuba's ptracer traces spp x width x height paths). Which renderer goes first
alternates from round to round, so a drift in machine load does not favour one side.

Timing. Mitsuba: the wall time of mi.render(scene, integrator, spp=N, seed) with the result
copied to numpy inside the timing (so the kernel has run), after one untimed warm-up render of
the same size per scene, variant, thread count and integrator (the JIT compile is excluded; a
timed render that compiled a kernel anyway is flagged). Threads: drjit.set_thread_count(n), the
nanothread pool Mitsuba's scalar and LLVM variants both render on. lt: the `seconds` of the JSON
record `lt render … -o X.exr` writes as X.json, which is the pass loop only (scene load and BVH
build excluded, as Mitsuba's load is); `--threads n --quiet`.

The machine may be shared, so each render records the 1-minute load average (/proc/loadavg)
just before it and its CPU use over wall time ("cpu": Mitsuba's over the timed render, lt's over
its whole process; an n-thread render on n idle cores is near n, much less means it was starved).
Throughputs vary from run to run by ±20 % on a shared machine: compare the ratios, measured back
to back, more than the absolute figures.

Quirks (Mitsuba 3.9.1, Dr.Jit 1.5): drjit.set_thread_count(n) works at any time, also between
renders of a loaded scene; but reading an EXR through mi.Bitmap with a one-thread pool deadlocks,
so lt's images are read with the pool briefly set to two threads (outside any timing). The LLVM
variant renders all spp x pixels of a call as one wavefront, so its throughput depends somewhat
on --spp; keep the same --spp when comparing runs.

Image check: the mean pixel value (over pixels and RGB) of lt's and Mitsuba's image of every
render, and their relative difference ("Δmean"); a difference well beyond the noise (a few % at
a few spp) means the scene was converted wrongly, and the throughputs compare different work.
"""
import argparse
import datetime
import hashlib
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
sys.dont_write_bytecode = True  # no __pycache__ beside the scripts in the repo
sys.path.insert(0, HERE)
from mitsuba_reference import find_libllvm  # noqa: E402

DEFAULT_SCENES = ["scenes/cornell-box.toml", "scenes/bench/cornell-glossy-glass.toml"]
# (Mitsuba integrator, lt integrator): the same estimator on both sides.
PAIRS = [("path", "pt"), ("ptracer", "light")]
MAX_DEPTH = 8  # --max-depth
RR_DEPTH = 5  # --rr-depth
DEFINES = []  # -D key=value: an XML scene's parameters, for both renderers


# ---------------------------------------------------------------------------------------------
# Machine state


def load1():
    """The 1-minute load average."""
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def uptime_line():
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        with open("/proc/loadavg") as f:
            return "loadavg " + f.read().strip()


def cpu_self():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def git_state():
    try:
        head = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", REPO, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return head + (" (work tree has uncommitted changes)" if dirty else "")
    except OSError:
        return "unknown"


# ---------------------------------------------------------------------------------------------
# lt


def resolve_lt(explicit, work):
    """The lt binary to run: --lt as given, else a private copy of target/release/lt (so a rebuild
    during the run cannot swap the binary between rounds)."""
    if explicit:
        path = os.path.abspath(explicit)
        if not os.access(path, os.X_OK):
            sys.exit(f"--lt {explicit}: not an executable file")
        return path
    built = os.path.join(REPO, "target", "release", "lt")
    if not os.path.exists(built):
        sys.exit("no target/release/lt: run `cargo build --release --bin lt` or pass --lt PATH")
    copy = os.path.join(work, "lt")
    shutil.copy2(built, copy)
    return copy


def lt_identity(lt):
    with open(lt, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:12]
    mtime = datetime.datetime.fromtimestamp(os.path.getmtime(lt)).strftime("%Y-%m-%d %H:%M")
    return f"{lt} (sha256 {digest}…, built {mtime})"


def lt_convert(lt, scene, xml):
    r = subprocess.run([lt, "convert", scene, "-o", xml], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"lt convert {scene} failed: {r.stderr.strip()}")


# Extra `lt render` arguments for every render (--lt-ray-core).
LT_EXTRA = []


def lt_render(lt, scene, integrator, spp, threads, seed, out_exr, extra=()):
    """Runs `lt render`; returns its JSON record plus wall/cpu of the whole process and load1."""
    before = load1()
    cmd = [lt, "render", scene, "-i", integrator, "--spp", str(spp), "--threads", str(threads),
           "--seed", str(seed), "--max-depth", str(MAX_DEPTH), "--rr-depth", str(RR_DEPTH),
           "--quiet", "-o", out_exr, *LT_EXTRA, *extra]
    for k, v in DEFINES:
        cmd += ["-D", f"{k}={v}"]
    c0 = cpu_children()
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    cpu = cpu_children() - c0
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr.strip()}")
    with open(os.path.splitext(out_exr)[0] + ".json") as f:
        rec = json.load(f)
    if rec.get("spp") != spp or rec.get("interrupted"):
        sys.exit(f"lt rendered {rec.get('spp')} of {spp} spp (interrupted: {rec.get('interrupted')})")
    secs = float(rec["seconds"])
    return {
        "seconds": secs,
        "spp_per_s": spp / secs,
        # CPU seconds of the pass loop's threads (lt's own record).
        "cpu_seconds": float(rec.get("cpu_seconds", float("nan"))),
        "process_wall": wall,
        # The whole process's CPU time over its wall time (the pass loop cannot be told apart from
        # outside): near `threads` on an idle machine when the pass loop dominates, lower when a
        # long one-thread scene load does.
        "cpu": cpu / max(wall, 1e-9),
        # Everything outside the pass loop: start-up, scene load, BVH build, writing the images.
        "outside_loop": wall - secs,
        "load1": before,
        "record": rec,
    }


# ---------------------------------------------------------------------------------------------
# Mitsuba (in this process)


class Mitsuba:
    def __init__(self):
        if "DRJIT_LIBLLVM_PATH" not in os.environ:
            lib = find_libllvm()
            if lib:
                os.environ["DRJIT_LIBLLVM_PATH"] = lib
        import drjit as dr
        import mitsuba as mi
        import numpy as np
        self.dr, self.mi, self.np = dr, mi, np
        self.variant = None
        self.version = f"mitsuba {mi.__version__}, drjit {dr.__version__}"

    def set_variant(self, variant):
        mi, dr = self.mi, self.dr
        if variant not in mi.variants():
            sys.exit(f"Mitsuba variant {variant} is not available (have {', '.join(mi.variants())})")
        mi.set_variant(variant)
        self.variant = variant
        self.jit = variant.startswith("llvm") or variant.startswith("cuda")
        if self.jit:
            # Lets a timed render tell whether it compiled a kernel (it should not after warm-up).
            dr.set_flag(dr.JitFlag.KernelHistory, True)

    def load(self, xml):
        t0 = time.perf_counter()
        scene = self.mi.load_file(xml, **dict(DEFINES))
        return scene, time.perf_counter() - t0

    def integrator(self, kind):
        return self.mi.load_dict({"type": kind, "max_depth": MAX_DEPTH, "rr_depth": RR_DEPTH})

    def set_threads(self, n):
        self.dr.set_thread_count(n)
        if self.dr.thread_count() != n:
            sys.exit(f"drjit.set_thread_count({n}) left thread_count() = {self.dr.thread_count()}")

    def _compiles(self):
        if not self.jit:
            return 0
        hist = self.dr.kernel_history()
        return sum(1 for k in hist
                   if str(k.get("type")).endswith("JIT") and not k.get("cache_hit", 1))

    def render(self, scene, integrator, spp, seed):
        """One timed render; returns the figures and the image as a numpy array (H, W, 3)."""
        self._compiles()  # clears the kernel history
        before = load1()
        c0 = cpu_self()
        t0 = time.perf_counter()
        img = self.mi.render(scene, integrator=integrator, spp=spp, seed=seed)
        arr = self.np.array(img)  # waits for the kernels: the timing covers the whole render
        secs = time.perf_counter() - t0
        cpu = cpu_self() - c0
        return {
            "seconds": secs,
            "spp_per_s": spp / secs,
            "cpu_seconds": cpu,
            "cpu": cpu / max(secs, 1e-9),
            "load1": before,
            "compiled": self._compiles(),
        }, arr[..., :3]

    def read_exr(self, path):
        # Mitsuba 3.9.1 / Dr.Jit 1.5: reading an EXR with a one-thread pool deadlocks (the loader
        # waits on a pool task the pool never runs), so read with two threads and set back.
        n = self.dr.thread_count()
        if n < 2:
            self.dr.set_thread_count(2)
        try:
            return self.np.array(self.mi.Bitmap(path))[..., :3]
        finally:
            if n < 2:
                self.dr.set_thread_count(n)


# ---------------------------------------------------------------------------------------------
# Scene facts and tables


def xml_facts(xml):
    """Resolution, filter and max depth as the converted XML states them."""
    root = ET.parse(xml).getroot()
    if root.find("./sensor/film") is None:
        # A suite scene: its film sits in an <include>d file, sized by $res.
        return None
    film = root.find("./sensor/film")
    w = int(film.find("./integer[@name='width']").get("value"))
    h = int(film.find("./integer[@name='height']").get("value"))
    rf = film.find("./rfilter")
    md = root.find("./integrator/integer[@name='max_depth']")
    return {
        "width": w,
        "height": h,
        "rfilter": rf.get("type") if rf is not None else "gaussian (hdrfilm default)",
        "max_depth": int(md.get("value")) if md is not None else None,
    }


def display_path(path):
    """A path inside the repository relative to it; any other as it is."""
    rel = os.path.relpath(path, REPO)
    return path if rel.startswith("..") else rel


# Samples per pixel of the render-test suite's references (its README).
SUITE_REF_SPP = 32_000


def reference_of(mitsuba, scene):
    """Mitsuba's reference image of a render-test suite scene (`refs/<name without the
    integrator suffix>_ref_rgb.exr` beside it) as (path, image, its own mean squared error: the
    mean per-sample variance of `_var` over the reference's spp), or None."""
    stem = os.path.splitext(os.path.basename(scene))[0]
    for suffix in ("_volpathmis", "_volpath", "_path"):
        if stem.endswith(suffix):
            stem = stem[: -len(suffix)]
            break
    path = os.path.join(os.path.dirname(scene), "refs", stem + "_ref_rgb.exr")
    if not os.path.exists(path):
        return None
    var_path = path[: -len(".exr")] + "_var.exr"
    var = float(mitsuba.read_exr(var_path).mean()) if os.path.exists(var_path) else 0.0
    return path, mitsuba.read_exr(path), var / SUITE_REF_SPP


def mse_star(img, ref):
    """Mean squared error of `img` against the reference (path, image, noise), its noise
    subtracted; None when there is no reference or its size differs."""
    if ref is None or ref[1].shape != img.shape:
        return None
    return float(((img - ref[1]) ** 2).mean()) - ref[2]


def fmt_mse(x):
    return "—" if x is None else f"{x:.3e}"


def median_range(xs):
    return statistics.median(xs), min(xs), max(xs)


def fmt_ratio_summary(xs):
    m, lo, hi = median_range(xs)
    return f"**{m:.2f}** [{lo:.2f}, {hi:.2f}]"


def mean_diff(a, b):
    return (a / b - 1.0) if b != 0 else float("inf")


def parse_int_list(values):
    out = []
    for v in values:
        out.extend(int(x) for x in str(v).split(",") if x.strip())
    return out


def parse_str_list(values):
    out = []
    for v in values:
        out.extend(x.strip() for x in str(v).split(",") if x.strip())
    return out


def write_report(path, lines):
    """The report's lines to `path` (folders made as needed)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"\nwrote {path}")


def header_lines(args, lt, mitsuba, extra=()):
    lines = [
        f"Command: `{' '.join([os.path.relpath(sys.argv[0], REPO) if sys.argv[0].startswith(REPO) else sys.argv[0]] + sys.argv[1:])}`  ",
        f"Date: {datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}; repo {git_state()}  ",
        f"Machine: {os.cpu_count()} hardware threads, {cpu_model()}; at start: `{uptime_line()}`  ",
        f"lt: {lt_identity(lt)}  ",
        f"Mitsuba: {mitsuba.version}; DRJIT_LIBLLVM_PATH={os.environ.get('DRJIT_LIBLLVM_PATH', '(unset)')}  ",
    ]
    lines.extend(extra)
    return lines


# ---------------------------------------------------------------------------------------------


def main():
    global MAX_DEPTH, RR_DEPTH
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n".join(__doc__.split("\n")[1:]))
    ap.add_argument("--lt", default=None,
                    help="lt binary (default: a private copy of target/release/lt)")
    ap.add_argument("--scenes", nargs="+", default=None, help=f"TOML scenes (default {' '.join(DEFAULT_SCENES)})")
    ap.add_argument("--spp", type=int, default=None, help="samples per pixel of every render (default 64)")
    ap.add_argument("--rounds", type=int, default=None, help="rounds per scene and thread count (default 7)")
    ap.add_argument("--threads", nargs="+", default=["2"], help="thread counts, e.g. 1 2 (default 2)")
    ap.add_argument("--variants", nargs="+", default=["llvm_ad_rgb"],
                    help="Mitsuba variants (default llvm_ad_rgb; scalar_rgb also works)")
    ap.add_argument("--pairs", default="path:pt,ptracer:light",
                    help="Mitsuba:lt integrator pairs (default path:pt,ptracer:light)")
    ap.add_argument("--out", default=None, help="also write the Markdown here")
    ap.add_argument("--work", default=None, help="folder for the XML and images (default: a temporary one)")
    ap.add_argument("--quick", action="store_true", help="smoke test: 4 spp, 1 round")
    ap.add_argument("--max-depth", type=int, default=MAX_DEPTH, help=f"both renderers (default {MAX_DEPTH})")
    ap.add_argument("--rr-depth", type=int, default=RR_DEPTH, help=f"both renderers (default {RR_DEPTH})")
    ap.add_argument("--lt-ray-core", default=None,
                    help="lt's --ray-core for every lt render (e.g. embree: the BVH library Mitsuba's "
                         "PyPI builds trace with); default lt's auto")
    ap.add_argument("-D", dest="define", action="append", default=[], metavar="KEY=VALUE",
                    help="an XML scene's $KEY for both renderers (repeatable)")
    a = ap.parse_args()
    MAX_DEPTH, RR_DEPTH = a.max_depth, a.rr_depth
    if a.lt_ray_core:
        LT_EXTRA.extend(["--ray-core", a.lt_ray_core])
    for d in a.define:
        if "=" not in d:
            sys.exit(f"-D {d}: expected KEY=VALUE")
        DEFINES.append(tuple(d.split("=", 1)))
    spp = a.spp or (4 if a.quick else 64)
    rounds = a.rounds or (1 if a.quick else 7)
    threads = parse_int_list(a.threads)
    variants = parse_str_list(a.variants)
    pairs = [tuple(p.split(":")) for p in parse_str_list([a.pairs])]
    if spp < 1 or rounds < 1 or not threads or min(threads) < 1:
        sys.exit("--spp, --rounds and --threads must be at least 1")
    scenes = [os.path.abspath(os.path.join(REPO, s) if not os.path.exists(s) else s)
              for s in (a.scenes or DEFAULT_SCENES)]

    tmp = None
    if a.work:
        work = os.path.abspath(a.work)
        os.makedirs(work, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="bench-vs-mitsuba-")
        work = tmp.name
    lt = resolve_lt(a.lt, work)
    mitsuba = Mitsuba()

    out = header_lines(a, lt, mitsuba, [
        f"Settings: {spp} spp per render, {rounds} round(s), threads {threads}, variants {variants}, "
        f"max depth {MAX_DEPTH}, rr depth {RR_DEPTH}. Light tracing's spp = light paths per pixel "
        "(pixel count per pass). spp/s = spp / seconds of the render (lt: its pass loop; Mitsuba: "
        "mi.render after a warm-up). cpu = CPU seconds / wall seconds (Mitsuba: of the render; lt: "
        "of its whole process, scene load included); near the thread count on an idle machine. "
        "load = 1-min load average just before the render. "
        "Δmean = mean pixel of lt / Mitsuba − 1 (a few % is noise at few spp). lt/Mitsuba by CPU time = "
        "Mitsuba's CPU seconds over lt's (lt: its pass loop's threads; Mitsuba: this process during "
        "mi.render) at equal spp, which a machine shared with other work disturbs less than wall time.",
        "",
    ])
    print("\n".join(out), flush=True)
    summary = []  # (scene, variant, threads, pair, ratios, mean diffs)

    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        if scene.endswith(".xml"):
            # A Mitsuba scene: both renderers read the same file.
            xml = scene
            defs = ", ".join(f"{k}={v}" for k, v in DEFINES) or "none"
            note = (f"## {name}\n\n`{display_path(scene)}`, Mitsuba XML read by both (-D: {defs}); "
                    f"both renderers are run at max depth {MAX_DEPTH}.\n")
        else:
            xml = os.path.join(work, name + ".xml")
            lt_convert(lt, scene, xml)
            facts = xml_facts(xml)
            note = (f"## {name}\n\n`{display_path(scene)}` → `lt convert` → Mitsuba: "
                    f"{facts['width']}×{facts['height']}, rfilter {facts['rfilter']}, scene max_depth "
                    f"{facts['max_depth']} (both renderers are run at {MAX_DEPTH}).\n")
            if facts["max_depth"] != MAX_DEPTH:
                note += f"\n**Note**: the scene says max_depth {facts['max_depth']}; rendered at {MAX_DEPTH}.\n"
        ref = reference_of(mitsuba, scene)
        if ref is not None:
            note += (f"\nReference: `{display_path(ref[0])}` (its own noise, mean of the `_var` image "
                     f"/ {SUITE_REF_SPP} spp: {ref[2]:.3g}, subtracted from each MSE: MSE*).\n")
        print(note, flush=True)
        out.append(note)
        # One untimed lt render: checks the scene and warms the page cache.
        lt_render(lt, scene, "pt", 1, max(threads), 0, os.path.join(work, f"{name}-lt-warm.exr"))
        for variant in variants:
            mitsuba.set_variant(variant)
            mscene, load_secs = mitsuba.load(xml)
            integrators = {m: mitsuba.integrator(m) for m, _ in pairs}
            for n in threads:
                mitsuba.set_threads(n)
                for m_int, lt_int in pairs:
                    # Warm-up: compiles (LLVM) and caches the kernels of this render size.
                    t0 = time.perf_counter()
                    mitsuba.render(mscene, integrators[m_int], spp, seed=100_000)
                    warm = time.perf_counter() - t0
                    title = (f"### {name}: Mitsuba {variant} `{m_int}` vs lt `{lt_int}`, {n} thread(s), "
                             f"{spp} spp")
                    rows = [title, "",
                            f"Mitsuba scene load {load_secs:.2f} s; warm-up render (incl. JIT) {warm:.2f} s.",
                            "",
                            "| round | first | lt spp/s | lt cpu | lt load | Mitsuba spp/s | Mitsuba cpu | Mitsuba load "
                            "| **lt/Mitsuba** | mean lt | mean Mitsuba | Δmean | lt/Mitsuba by CPU time |"
                            + (" MSE* lt | MSE* Mitsuba | **efficiency lt/Mitsuba** |" if ref else ""),
                            "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
                            + ("---:|---:|---:|" if ref else "")]
                    print("\n".join(rows), flush=True)
                    ratios, diffs, effs, cpu_ratios = [], [], [], []
                    for r in range(rounds):
                        seed = r + 1
                        exr = os.path.join(work, f"{name}-{lt_int}.exr")
                        lt_first = r % 2 == 1
                        if lt_first:
                            ltr = lt_render(lt, scene, lt_int, spp, n, seed, exr)
                            mir, mimg = mitsuba.render(mscene, integrators[m_int], spp, seed)
                        else:
                            mir, mimg = mitsuba.render(mscene, integrators[m_int], spp, seed)
                            ltr = lt_render(lt, scene, lt_int, spp, n, seed, exr)
                        limg = mitsuba.read_exr(exr)
                        lt_mean = float(limg.mean())
                        mi_mean = float(mimg.mean())
                        # Equal error: efficiency 1/(MSE* · seconds), lt over Mitsuba.
                        mse_lt, mse_mi = mse_star(limg, ref), mse_star(mimg, ref)
                        eff = None
                        if mse_lt is not None and mse_lt > 0 and mse_mi > 0:
                            eff = (mse_mi * mir["seconds"]) / (mse_lt * ltr["seconds"])
                            effs.append(eff)
                        ratio = ltr["spp_per_s"] / mir["spp_per_s"]
                        # On a shared machine the CPU seconds each spent, Mitsuba's over lt's.
                        cpu_ratio = mir["cpu_seconds"] / ltr["cpu_seconds"]
                        cpu_ratios.append(cpu_ratio)
                        d = mean_diff(lt_mean, mi_mean)
                        ratios.append(ratio)
                        diffs.append(d)
                        flag = f" (compiled {mir['compiled']} kernel(s) while timed!)" if mir["compiled"] else ""
                        row = (f"| {r + 1} | {'lt' if lt_first else 'Mitsuba'} | {ltr['spp_per_s']:.2f} | "
                               f"{ltr['cpu']:.2f} | {ltr['load1']:.2f} | {mir['spp_per_s']:.2f}{flag} | "
                               f"{mir['cpu']:.2f} | {mir['load1']:.2f} | **{ratio:.2f}** | {lt_mean:.4f} | "
                               f"{mi_mean:.4f} | {100 * d:+.1f} % | {cpu_ratio:.2f} |")
                        if ref:
                            row += (f" {fmt_mse(mse_lt)} | {fmt_mse(mse_mi)} | "
                                    + (f"**{eff:.2f}** |" if eff is not None else "— |"))
                        print(row, flush=True)
                        rows.append(row)
                    tail = [f"| **median [min, max]** | | | | | | | | {fmt_ratio_summary(ratios)} | | | "
                            f"{100 * statistics.median(diffs):+.1f} % | {fmt_ratio_summary(cpu_ratios)} |"
                            + (f" | | {fmt_ratio_summary(effs)} |" if effs else (" | | |" if ref else "")), ""]
                    print("\n".join(tail), flush=True)
                    rows.extend(tail)
                    out.extend(rows)
                    summary.append((name, variant, n, f"{m_int} / {lt_int}", ratios, diffs, effs, cpu_ratios))

    s = ["## Summary: lt throughput / Mitsuba throughput (median over rounds [min, max])", "",
         "| scene | Mitsuba variant | threads | Mitsuba / lt integrator | lt/Mitsuba | Δmean (median) | rounds "
         "| lt/Mitsuba by CPU time | efficiency lt/Mitsuba at equal error |",
         "|---|---|---:|---|---:|---:|---:|---:|---:|"]
    warn = []
    for name, variant, n, pair, ratios, diffs, effs, cpu_ratios in summary:
        md = statistics.median(diffs)
        s.append(f"| {name} | {variant} | {n} | {pair} | {fmt_ratio_summary(ratios)} | {100 * md:+.1f} % | "
                 f"{len(ratios)} | {fmt_ratio_summary(cpu_ratios)} | "
                 f"{fmt_ratio_summary(effs) if effs else '— (no reference)'} |")
        if abs(md) > 0.05:
            warn.append(f"- **image check**: {name} {pair} ({variant}): mean pixel differs by "
                        f"{100 * md:+.1f} % — check the conversion before trusting the ratio.")
    s.append("")
    s.append(f"At end: `{uptime_line()}`")
    s.extend([""] + warn if warn else [])
    print("\n".join(s), flush=True)
    out.extend(s)
    if a.out:
        write_report(a.out, out)
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    main()
