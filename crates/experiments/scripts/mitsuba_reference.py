#!/usr/bin/env python3
"""Render a scene with Mitsuba 3: the independent reference for our estimators.

SCENE is one of our TOML scenes (converted first with `lt convert`, so any shipped scene Mitsuba
can express renders here; a scene with a finite-cone sun is refused by the converter), a Mitsuba
XML file, or nothing for Mitsuba's built-in cornell_box() with a box pixel filter (the scene
scenes/cornell-box.toml was made from). Renders K independent seeds and writes their per-pixel
mean and standard error of the mean, so `lt compare` can run a per-block z-test between our image
and Mitsuba's:

    pip install mitsuba
    python3 crates/experiments/scripts/mitsuba_reference.py scenes/veach-mis.toml --spp 256 --seeds 8
    lt render scenes/veach-mis.toml -i pt --spp 1024 -o results/veach-mis/pt.exr
    lt compare results/veach-mis/pt.exr results/veach-mis/mitsuba.exr \
        --a-stderr results/veach-mis/pt.stderr.exr --b-stderr results/veach-mis/mitsuba.stderr.exr

Writes OUT.exr, OUT.stderr.exr and OUT.json (how it was made; default OUT is
results/<scene>/mitsuba). The `scalar_rgb` variant needs nothing else; an LLVM variant needs
libLLVM, which is looked for under /usr/lib when DRJIT_LIBLLVM_PATH is not set.
"""
import argparse
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def find_libllvm():
    """The newest libLLVM under /usr/lib (Dr.Jit 1.5 rejects LLVM 14; 15 and later work)."""
    import re
    hits = set()
    for pattern in ["/usr/lib/llvm-*/lib/libLLVM*.so*", "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
                    "/usr/lib/libLLVM*.so*"]:
        hits.update(glob.glob(pattern))

    def major(path):
        m = re.search(r"libLLVM-?(\d+)", os.path.basename(path)) or re.search(r"llvm-(\d+)", path)
        return int(m.group(1)) if m else 0

    best = sorted(hits, key=lambda p: (major(p), -len(p)))
    return best[-1] if best else None


def lt_command(explicit):
    if explicit:
        return [explicit]
    built = os.path.join(REPO, "target", "release", "lt")
    if os.path.exists(built):
        return [built]
    if shutil.which("lt"):
        return ["lt"]
    return ["cargo", "run", "--quiet", "--release", "--bin", "lt", "--"]


def scene_name(path):
    if path is None:
        return "cornell-box"
    return os.path.splitext(os.path.basename(path))[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?", help="our .toml scene, a Mitsuba .xml, or none for cornell_box()")
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each seed's render")
    ap.add_argument("--seeds", type=int, default=8, help="independent renders (standard error across them)")
    ap.add_argument("--integrator", default=None, help="path or ptracer (default: the scene's)")
    ap.add_argument("--max-depth", type=int, default=None, help="default: the scene's (8 for cornell_box())")
    ap.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), default=None)
    ap.add_argument("--lt", default=None, help="the lt binary used for `lt convert`")
    ap.add_argument("--out", default=None, help="output prefix (default results/<scene>/mitsuba)")
    a = ap.parse_args()
    if a.seeds < 1 or a.spp < 1:
        sys.exit("--seeds and --spp must be at least 1")
    if "llvm" in a.variant and "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    import mitsuba as mi
    import numpy as np

    mi.set_variant(a.variant)
    out = a.out or os.path.join("results", scene_name(a.scene), "mitsuba")
    source = "mitsuba.cornell_box()"
    xml_text = None
    if a.scene is None:
        d = mi.cornell_box()
        d["sensor"]["film"]["rfilter"] = {"type": "box"}
        if a.integrator or a.max_depth:
            d["integrator"] = {"type": a.integrator or "path", "max_depth": a.max_depth or 8}
        if a.resolution:
            d["sensor"]["film"]["width"], d["sensor"]["film"]["height"] = a.resolution
        scene = mi.load_dict(d)
    else:
        if a.integrator or a.max_depth or a.resolution:
            sys.exit("--integrator, --max-depth and --resolution apply to cornell_box() only: "
                     "a scene file says them itself (edit the XML lt convert writes)")
        path = a.scene
        with tempfile.TemporaryDirectory() as tmp:
            if path.lower().endswith(".toml"):
                xml = os.path.join(tmp, scene_name(path) + ".xml")
                r = subprocess.run(lt_command(a.lt) + ["convert", path, "-o", xml],
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    sys.exit(f"lt convert failed: {r.stderr.strip()}")
                source = f"{path} via lt convert"
            else:
                xml = path
                source = path
            with open(xml) as f:
                xml_text = f.read()
            scene = mi.load_file(xml)
    # One untimed warm-up render compiles kernels (LLVM variants) outside the timing.
    mi.render(scene, spp=1, seed=10_000)
    images = []
    start = time.perf_counter()
    for seed in range(a.seeds):
        img = np.array(mi.render(scene, spp=a.spp, seed=seed), dtype=np.float64)[:, :, :3]
        images.append(img)
    secs = time.perf_counter() - start
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    stderr = stack.std(axis=0, ddof=1) / np.sqrt(a.seeds) if a.seeds > 1 else np.zeros_like(mean)
    os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
    # Bitmap.write is synchronous (mi.util.write_bitmap may leave an empty file at exit).
    mi.Bitmap(mean.astype(np.float32)).write(out + ".exr")
    mi.Bitmap(stderr.astype(np.float32)).write(out + ".stderr.exr")
    total = a.spp * a.seeds
    record = {
        "renderer": f"mitsuba {mi.__version__}",
        "variant": a.variant,
        "scene": source,
        "spp_per_seed": a.spp,
        "seeds": list(range(a.seeds)),
        "std_error_source": "across seeds" if a.seeds > 1 else "none (one seed)",
        "seconds": secs,
        "integrator": str(scene.integrator()).split("[")[0],
        "width": int(mean.shape[1]),
        "height": int(mean.shape[0]),
    }
    if xml_text is not None:
        record["xml"] = xml_text
    with open(out + ".json", "w") as f:
        json.dump(record, f, indent=1)
    print(f"mitsuba {mi.__version__} {a.variant}: {source}: {total} spp in {secs:.2f} s "
          f"= {total / secs:.1f} spp/s -> {out}.exr")


if __name__ == "__main__":
    main()
