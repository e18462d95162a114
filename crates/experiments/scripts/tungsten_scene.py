#!/usr/bin/env python3
"""Write one of our TOML scenes (diffuse quads and cubes, an emitting quad, a pinhole camera: the
Cornell box) as a Tungsten scene (JSON), for the side-by-side benchmarks against Tungsten
(bench_peers.sh, tungsten_vs_lt.sh).

    tungsten_scene.py SCENE.toml OUT.json [--integrator path_tracer|light_tracer|
        bidirectional_path_tracer|progressive_photon_map] [--spp N] [--width W]
        [--set KEY=VALUE ...]

--set adds integrator fields (numbers or true/false), e.g. gather_radius=0.0225.

Shapes, in Tungsten's conventions (read from its source, src/core/primitives):
- our `quad` is Mitsuba's rectangle, [-1, 1]² in the local xy plane, normal M·x × M·y. Tungsten's
  `quad` is [-0.5, 0.5]² in the local xz plane, edges T·x and T·z, normal edge1 × edge0. So
  T·x = 2 M·y, T·z = 2 M·x (normal T·z × T·x = 4 M·x × M·y, the same side) and T·y = M·z.
- our `cube` is [-1, 1]³, Tungsten's [-0.5, 0.5]³: T = M with every column doubled.
Materials: `diffuse` becomes `lambert`. Emission is radiance in both. Our max_depth counts
segments with the camera ray; Tungsten's max_bounces counts the same segments on the paths it
lists in its own Cornell box (max_bounces = max_depth; checked by the images' agreement, see
results/bench.md).
"""
import argparse
import json
import sys

try:
    import tomllib
except ImportError:  # Python < 3.11
    sys.exit("tungsten_scene.py: needs Python 3.11 (tomllib)")


def fail(msg):
    sys.exit(f"tungsten_scene.py: {msg}")


def matrix(m, where):
    if len(m) != 4 or any(len(r) != 4 for r in m):
        fail(f"{where}: to_world must be 4 × 4")
    return [[float(x) for x in r] for r in m]


def quad_transform(m):
    col = lambda j: [m[i][j] for i in range(3)]
    x, y, z = col(0), col(1), col(2)
    t = [[2 * y[i], z[i], 2 * x[i], m[i][3]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    return [v for row in t for v in row]


def cube_transform(m):
    t = [[2 * m[i][0], 2 * m[i][1], 2 * m[i][2], m[i][3]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    return [v for row in t for v in row]


def value(text):
    if text in ("true", "false"):
        return text == "true"
    try:
        return int(text)
    except ValueError:
        return float(text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--integrator", default="path_tracer")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--width", type=int, default=0)
    ap.add_argument("--set", action="append", default=[])
    a = ap.parse_args()
    with open(a.scene, "rb") as f:
        s = tomllib.load(f)
    bsdfs = []
    for name, mat in s.get("materials", {}).items():
        if mat.get("type") != "diffuse":
            fail(f"{a.scene}: material '{name}' is {mat.get('type')}; only diffuse is converted")
        bsdfs.append({"name": name, "type": "lambert", "albedo": mat["albedo"]})
    prims = []
    for i, sh in enumerate(s.get("shapes", [])):
        where = f"{a.scene}: shapes[{i}]"
        m = matrix(sh.get("to_world", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), where)
        kind = sh.get("type")
        if kind == "quad":
            p = {"type": "quad", "transform": quad_transform(m)}
        elif kind == "cube":
            p = {"type": "cube", "transform": cube_transform(m)}
        else:
            fail(f"{where}: shape type '{kind}' is not converted (quad and cube are)")
        p["bsdf"] = sh["material"]
        if "emission" in sh:
            p["emission"] = sh["emission"]
        prims.append(p)
    cam = s["camera"]
    w, h = cam.get("resolution", [256, 256])
    if a.width:
        w, h = a.width, round(h * a.width / w)
    if w != h and cam.get("fov_axis", "x") != "x":
        fail(f"{a.scene}: fov_axis '{cam.get('fov_axis')}' on a non-square film is not converted")
    integrator = {
        "type": a.integrator,
        "min_bounces": 0,
        "max_bounces": int(s.get("render", {}).get("max_depth", 8)),
        "enable_consistency_checks": False,
        "enable_two_sided_shading": True,
    }
    for kv in a.set:
        k, _, v = kv.partition("=")
        integrator[k] = value(v)
    scene = {
        "media": [],
        "bsdfs": bsdfs,
        "primitives": prims,
        "camera": {
            "type": "pinhole",
            "tonemap": "linear",
            "resolution": [w, h],
            "reconstruction_filter": "box",
            "fov": float(cam["fov"]),
            "transform": {"position": cam["eye"], "look_at": cam["target"], "up": cam["up"]},
        },
        "integrator": integrator,
        "renderer": {
            "output_file": "tungsten.png",
            "hdr_output_file": "tungsten.pfm",
            "overwrite_output_files": True,
            "adaptive_sampling": False,
            "enable_resume_render": False,
            "stratified_sampler": False,
            "scene_bvh": True,
            "spp": a.spp,
            # Tungsten renders spp in segments of spp_step; its progressive photon map traces one
            # photon pass per segment (with spp_step camera samples), so 1 there: one spp = one
            # pass of photon_count photon paths and one camera sample per pixel, as our sppm.
            "spp_step": 1 if a.integrator == "progressive_photon_map" else a.spp,
            "checkpoint_interval": "0",
            "timeout": "0",
        },
    }
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(scene, f, indent=1)
    import os

    os.replace(tmp, a.out)


if __name__ == "__main__":
    main()
