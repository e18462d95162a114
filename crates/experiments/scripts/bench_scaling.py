#!/usr/bin/env python3
"""Scene-size scaling of lt against Mitsuba 3 (issue 15, "Speed"): path-tracing throughput as the
triangle count grows from 10^3 to 10^6.

Full run (about 4-6 minutes on an idle 2-core machine: 4 sizes x 2 thread counts x 3 rounds of a
32-spp lt and Mitsuba render, most of it the 1-thread ones; the 10^6-triangle OBJ is 38 MB, is
generated once into --work in ~2 s and then reused). Run it on an otherwise idle machine:

    pip install mitsuba numpy && apt-get install -y libllvm19     # as for bench_vs_mitsuba.py
    cargo build --release --bin lt && cp target/release/lt /tmp/lt-bench-binary
    python3 crates/experiments/scripts/bench_scaling.py --lt /tmp/lt-bench-binary \
        --sizes 1e3 1e4 1e5 1e6 --threads 1 2 --spp 32 --rounds 3 --out results/bench-scaling.md

Smoke test: add --quick (sizes 10^3 and 10^4 only, 4 spp, 1 round).

The scenes: scenes/cornell-box.toml plus one diffuse (the box's white) closed triangle mesh, a
bumpy sphere of radius ~0.3 floating above the boxes, tessellated as a latitude-longitude grid
to about N triangles (the exact count is in the table). The meshes are Wavefront OBJ without
normals (the one format lt's TOML scenes read; `lt convert` marks them `face_normals` for
Mitsuba, so both shade them flat) and are written, with a TOML scene per size, into --work
(default: <tmp>/lt-bench-scaling), never into the repository.

Per size and thread count: one untimed warm-up render on each side, then per round, back to
back (alternating which goes first), Mitsuba `path` (llvm_ad_rgb by default) and lt `pt`, max
depth 8, at the scene's 256 x 256. Timing as in bench_vs_mitsuba.py: Mitsuba's is mi.render after
warm-up with the image copied to numpy; lt's is the pass loop of its JSON record. Load columns:
Mitsuba's mi.load_file (OBJ parse and BVH build); lt's is the time of the whole `lt render`
process outside its pass loop (start-up, OBJ parse, BVH build and writing the 256² images — the
JSON record has no load time of its own; if a later lt writes one, its keys are listed too).
"""
import argparse
import math
import os
import statistics
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True  # no __pycache__ beside the scripts in the repo
sys.path.insert(0, HERE)
from bench_vs_mitsuba import (  # noqa: E402
    REPO, Mitsuba, fmt_ratio_summary, header_lines, lt_convert, lt_render, mean_diff,
    parse_int_list, parse_str_list, resolve_lt, uptime_line, write_report,
)

BASE_SCENE = os.path.join(REPO, "scenes", "cornell-box.toml")
MESH_VERSION = 1  # bump when the mesh generator changes, so stale files in --work are rewritten
# Where the mesh sits: unit bumpy sphere scaled and moved above the boxes, below the light.
MESH_SCALE = 0.3
MESH_TRANSLATE = [0.05, 0.4, 0.3]


def sphere_bands(target):
    """Latitude bands b (longitudes 2b) whose grid has 4 b (b - 1) triangles nearest target."""
    b = max(3, round(0.5 + math.sqrt(0.25 + target / 4.0)))
    return b


def write_bumpy_sphere(path, bands):
    """A closed latitude-longitude sphere (poles as single vertices) with radial bumps, as OBJ
    without normals; faces wound counter-clockwise seen from outside. Returns the triangle count."""
    import numpy as np
    lons = 2 * bands
    theta = np.pi * np.arange(1, bands) / bands              # interior rings
    phi = 2 * np.pi * np.arange(lons) / lons
    th, ph = np.meshgrid(theta, phi, indexing="ij")          # (bands-1, lons)
    r = 1.0 + 0.08 * np.sin(6 * th) * np.cos(5 * ph)         # bumps: not a flat-shaded sphere only
    ring = np.stack([r * np.sin(th) * np.cos(ph), r * np.cos(th), -r * np.sin(th) * np.sin(ph)], -1)
    verts = np.concatenate([[[0.0, 1.0, 0.0]], ring.reshape(-1, 3), [[0.0, -1.0, 0.0]]])
    top, bottom = 1, len(verts)                              # OBJ indices are 1-based
    idx = 2 + np.arange((bands - 1) * lons).reshape(bands - 1, lons)
    nxt = np.roll(idx, -1, axis=1)
    faces = [
        np.stack([np.full(lons, top), idx[0], nxt[0]], -1),                       # top cap
        np.stack([idx[:-1], idx[1:], nxt[1:]], -1).reshape(-1, 3),               # bands
        np.stack([idx[:-1], nxt[1:], nxt[:-1]], -1).reshape(-1, 3),
        np.stack([np.full(lons, bottom), nxt[-1], idx[-1]], -1),                 # bottom cap
    ]
    faces = np.concatenate(faces)
    tmp = path + ".partial"
    with open(tmp, "w") as f:
        f.write(f"# bumpy sphere, {len(verts)} vertices, {len(faces)} triangles "
                f"(bench_scaling.py, mesh version {MESH_VERSION})\n")
        np.savetxt(f, verts, fmt="v %.6f %.6f %.6f")
        np.savetxt(f, faces, fmt="f %d %d %d")
    os.replace(tmp, path)
    return len(faces)


def make_scene(work, target):
    """The mesh and the TOML scene for about `target` triangles; returns (scene path, triangles)."""
    bands = sphere_bands(target)
    tris = 4 * bands * (bands - 1)
    mesh = f"bumpy-sphere-{tris}-v{MESH_VERSION}.obj"
    mesh_path = os.path.join(work, mesh)
    if not os.path.exists(mesh_path):
        t0 = time.perf_counter()
        got = write_bumpy_sphere(mesh_path, bands)
        assert got == tris, (got, tris)
        print(f"wrote {mesh_path} ({tris} triangles, {os.path.getsize(mesh_path) / 1e6:.1f} MB) "
              f"in {time.perf_counter() - t0:.1f} s", flush=True)
    with open(BASE_SCENE) as f:
        base = f.read()
    scene = os.path.join(work, f"cornell-mesh-{tris}.toml")
    with open(scene, "w") as f:
        f.write(f"# Generated by crates/experiments/scripts/bench_scaling.py: scenes/cornell-box.toml plus a\n"
                f"# {tris}-triangle diffuse bumpy sphere.\n\n")
        f.write(base.rstrip("\n"))
        f.write(f"""

# scaling mesh: {tris} triangles
[[shapes]]
type = "mesh"
file = "{mesh}"
material = "white"
scale = {MESH_SCALE}
translate = {MESH_TRANSLATE}
""")
    return scene, tris


def parse_sizes(values):
    return [int(float(x)) for x in parse_str_list(values)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n".join(__doc__.split("\n")[1:]))
    ap.add_argument("--lt", default=None, help="lt binary (default: a private copy of target/release/lt)")
    ap.add_argument("--sizes", nargs="+", default=None,
                    help="triangle counts (about), e.g. 1e3 1e4 1e5 1e6 (the default)")
    ap.add_argument("--threads", nargs="+", default=["1", "2"], help="thread counts (default 1 2)")
    ap.add_argument("--spp", type=int, default=None, help="samples per pixel of every render (default 32)")
    ap.add_argument("--rounds", type=int, default=None, help="rounds per size and thread count (default 3)")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default llvm_ad_rgb)")
    ap.add_argument("--out", default=None, help="also write the Markdown here")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "lt-bench-scaling"),
                    help="folder for meshes, scenes and images (default <tmp>/lt-bench-scaling; "
                         "meshes are reused from it)")
    ap.add_argument("--quick", action="store_true", help="smoke test: sizes 1e3 1e4, 4 spp, 1 round")
    a = ap.parse_args()
    sizes = parse_sizes(a.sizes) if a.sizes else ([1000, 10000] if a.quick else [1000, 10000, 100000, 1000000])
    spp = a.spp or (4 if a.quick else 32)
    rounds = a.rounds or (1 if a.quick else 3)
    threads = parse_int_list(a.threads)
    if spp < 1 or rounds < 1 or not threads or min(threads) < 1 or min(sizes) < 1:
        sys.exit("--spp, --rounds, --threads and --sizes must be at least 1")
    work = os.path.abspath(a.work)
    if os.path.commonpath([work, REPO]) == REPO:
        sys.exit(f"--work {work} is inside the repository: the meshes must not be committed")
    os.makedirs(work, exist_ok=True)
    lt = resolve_lt(a.lt, work)
    mitsuba = Mitsuba()
    mitsuba.set_variant(a.variant)

    out = header_lines(a, lt, mitsuba, [
        f"Settings: Mitsuba {a.variant} `path` vs lt `pt`, {spp} spp per render, {rounds} round(s), "
        f"threads {threads}, max depth 8, 256×256; scene = scenes/cornell-box.toml + a diffuse bumpy "
        "sphere of N triangles. spp/s: lt's pass loop, Mitsuba's mi.render after warm-up (medians "
        "over rounds). lt/Mi = median of the per-round ratios [min, max]. Load: Mitsuba mi.load_file; "
        "lt = its process's wall time outside the pass loop (start-up, OBJ parse, BVH build, image "
        "writing), median. cpu = CPU seconds / wall seconds (Mitsuba: of the render; lt: of its whole "
        "process, so a long one-thread load pulls it down). load1 = highest 1-min load average seen before a render of the row. "
        "Δmean = mean pixel lt / Mitsuba − 1.",
        "",
        "| triangles | threads | lt spp/s | Mitsuba spp/s | **lt/Mitsuba** | lt load (s) | Mitsuba load (s) "
        "| lt cpu | Mitsuba cpu | load1 | Δmean |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ])
    print("\n".join(out), flush=True)
    notes = []
    for target in sizes:
        scene, tris = make_scene(work, target)
        xml = os.path.splitext(scene)[0] + ".xml"
        lt_convert(lt, scene, xml)
        mscene, m_load = mitsuba.load(xml)
        integ = mitsuba.integrator("path")
        exr = os.path.splitext(scene)[0] + "-pt.exr"
        for n in threads:
            mitsuba.set_threads(n)
            mitsuba.render(mscene, integ, spp, seed=100_000)               # warm-up (JIT)
            lt_render(lt, scene, "pt", 1, n, 0, exr)                       # warm-up (page cache)
            lt_rates, mi_rates, ratios, lt_loads, lt_cpu, mi_cpu, loads, diffs = ([] for _ in range(8))
            for r in range(rounds):
                if r % 2 == 1:
                    ltr = lt_render(lt, scene, "pt", spp, n, r + 1, exr)
                    mir, mimg = mitsuba.render(mscene, integ, spp, r + 1)
                else:
                    mir, mimg = mitsuba.render(mscene, integ, spp, r + 1)
                    ltr = lt_render(lt, scene, "pt", spp, n, r + 1, exr)
                if mir["compiled"]:
                    notes.append(f"- {tris} triangles, {n} thread(s), round {r + 1}: Mitsuba compiled "
                                 f"{mir['compiled']} kernel(s) inside the timing.")
                extra = {k: v for k, v in ltr["record"].items()
                         if any(w in k for w in ("load", "build", "bvh")) and v is not None}
                if extra and r == 0:
                    notes.append(f"- {tris} triangles: lt's JSON record also says {extra}.")
                lt_rates.append(ltr["spp_per_s"])
                mi_rates.append(mir["spp_per_s"])
                ratios.append(ltr["spp_per_s"] / mir["spp_per_s"])
                lt_loads.append(ltr["outside_loop"])
                lt_cpu.append(ltr["cpu"])
                mi_cpu.append(mir["cpu"])
                loads.extend([ltr["load1"], mir["load1"]])
                diffs.append(mean_diff(float(mitsuba.read_exr(exr).mean()), float(mimg.mean())))
            med = statistics.median
            row = (f"| {tris:,} | {n} | {med(lt_rates):.2f} | {med(mi_rates):.2f} | {fmt_ratio_summary(ratios)} | "
                   f"{med(lt_loads):.2f} | {m_load:.2f} | {med(lt_cpu):.2f} | {med(mi_cpu):.2f} | "
                   f"{max(loads):.2f} | {100 * med(diffs):+.1f} % |")
            print(row, flush=True)
            out.append(row)
            if abs(med(diffs)) > 0.05:
                notes.append(f"- **image check**: {tris} triangles, {n} thread(s): mean pixel differs by "
                             f"{100 * med(diffs):+.1f} %.")
        del mscene
    tail = ["", f"At end: `{uptime_line()}`"] + ([""] + notes if notes else [])
    print("\n".join(tail), flush=True)
    out.extend(tail)
    if a.out:
        write_report(a.out, out)


if __name__ == "__main__":
    main()
