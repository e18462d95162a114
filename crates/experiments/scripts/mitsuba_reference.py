#!/usr/bin/env python3
"""Render Mitsuba 3's built-in cornell_box() as the independent reference for scenes/cornell-box.

Box pixel filter (ours is a box filter too), max depth 8, Mitsuba's default Russian roulette.
Renders K independent seeds and writes their per-pixel mean and standard error of the mean, so
`lt compare` can run a per-block z-test between our image and Mitsuba's. Prints spp/s.

    pip install mitsuba
    python3 crates/experiments/scripts/mitsuba_reference.py --spp 256 --seeds 8 --out results/cornell-box/mitsuba
"""
import argparse
import os
import time

import mitsuba as mi
import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--integrator", default="path", help="path or ptracer")
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--out", default="results/cornell-box/mitsuba")
    a = ap.parse_args()
    mi.set_variant(a.variant)
    scene_dict = mi.cornell_box()
    scene_dict["integrator"] = {"type": a.integrator, "max_depth": a.max_depth}
    scene_dict["sensor"]["film"]["rfilter"] = {"type": "box"}
    scene_dict["sensor"]["film"]["width"] = 256
    scene_dict["sensor"]["film"]["height"] = 256
    scene_dict["sensor"]["sampler"]["sample_count"] = a.spp
    scene = mi.load_dict(scene_dict)
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
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    mi.Bitmap(mean.astype(np.float32)).write(a.out + ".exr")
    mi.Bitmap(stderr.astype(np.float32)).write(a.out + ".stderr.exr")
    total = a.spp * a.seeds
    print(f"mitsuba {mi.__version__} {a.variant} {a.integrator}: {total} spp in {secs:.2f} s = {total / secs:.1f} spp/s")


if __name__ == "__main__":
    main()
