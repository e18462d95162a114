#!/usr/bin/env python3
"""Write one of our TOML scenes (diffuse quads and cubes, emitting quads, a pinhole camera: the
Cornell box) as a pbrt-v4 scene, for the side-by-side runs against pbrt-v4 (issues 46 item 7 and
47 item 1; pbrt built by build_pbrt_v4.sh).

    pbrt_scene.py SCENE.toml OUT.pbrt [--integrator path|bdpt|mlt|sppm] [--spp N]
        [--width W] [--exr OUT.exr] [--sampler zsobol|independent] [--set TYPE:NAME=VALUE ...]
    pbrt_scene.py SCENE.xml OUT.pbrt [the same] [-D KEY=VALUE ...] [--ggx-for-beckmann]
        --lt-xml LT.xml

A Mitsuba XML scene (Bitterli's veach-bidir and its kind; pbrt_from_mitsuba.py says which
subset) is converted too; LT.xml is the copy lt must render (file names absolute, and with
--ggx-for-beckmann its Beckmann conductors made GGX, the one distribution pbrt-v4's conductor has).

--set adds integrator parameters in pbrt's own words, e.g. `--set float:sigma=0.01`,
`--set integer:bootstrapsamples=100000`, `--set float:radius=0.01`.

Conventions (read from pbrt-v4's source and documentation, checked by the images' agreement with
lt's, see results/bench-peers.md):
- Geometry is written in world space as triangle meshes: our `quad` is Mitsuba's rectangle
  ([-1, 1]² in the local xy plane, normal +z local), our `cube` [-1, 1]³; each vertex is mapped
  through to_world here. pbrt's triangle normal for vertices (p0, p1, p2) is (p0 − p2) × (p1 − p2),
  so counter-clockwise corners seen from +z give +z: an emitting quad emits on the same side as
  ours (pbrt's `diffuse` area light is one-sided by default, like ours).
- pbrt's LookAt camera has image x along up × direction, the mirror of ours (forward × up), so
  `Scale -1 1 1` precedes it. pbrt's `fov` spans the shorter image axis (our fov_axis "smaller").
- Our max_depth counts segments, the camera ray included; pbrt's maxdepth counts bounces
  (maxdepth 0: emitters seen directly), so maxdepth = max_depth − 1 for path, bdpt, mlt and sppm.
- pbrt is spectral: RGB reflectances are upsampled to spectra (RGBAlbedoSpectrum) and RGB
  emission is an RGBIlluminantSpectrum normalised to one nit, so the image agrees with an RGB
  renderer's only to the spectral products' difference (stated beside each comparison).
- Pixel filter: box of radius 0.5 (one pixel), as ours; sampler named explicitly (the default
  zsobol; `pmj02bn` is unusable with build_pbrt_v4.sh's stand-in tables).
"""
import argparse
import math
import os
import sys

try:
    import tomllib
except ImportError:  # Python < 3.11
    sys.exit("pbrt_scene.py: needs Python 3.11 (tomllib)")


def fail(msg):
    sys.exit(f"pbrt_scene.py: {msg}")


def matrix(m, where):
    if len(m) != 4 or any(len(r) != 4 for r in m):
        fail(f"{where}: to_world must be 4 × 4")
    return [[float(x) for x in r] for r in m]


def apply(m, p):
    return [sum(m[i][j] * p[j] for j in range(3)) + m[i][3] for i in range(3)]


# Rectangle corners counter-clockwise seen from +z, two triangles.
QUAD = ([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [0, 1, 2, 0, 2, 3])
# Cube corners (bit 0: x, bit 1: y, bit 2: z) and its faces, each counter-clockwise from outside.
CUBE_P = [((i & 1) * 2 - 1, (i >> 1 & 1) * 2 - 1, (i >> 2 & 1) * 2 - 1) for i in range(8)]
CUBE_FACES = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
CUBE = (CUBE_P, [i for a, b, c, d in CUBE_FACES for i in (a, b, c, a, c, d)])


def nums(v):
    return " ".join(repr(float(x)) for x in v)


def mesh(points, indices, m):
    p = [c for q in points for c in apply(m, q)]
    return (f'Shape "trianglemesh" "integer indices" [ {" ".join(map(str, indices))} ]\n'
            f'    "point3 P" [ {nums(p)} ]\n')


def integrator_param(kv):
    key, _, v = kv.partition("=")
    kind, _, name = key.partition(":")
    if not name or kind not in ("integer", "float", "bool", "string"):
        fail(f"--set {kv}: expected TYPE:NAME=VALUE with TYPE integer, float, bool or string")
    val = f'"{v}"' if kind == "string" else v
    return f'"{kind} {name}" [ {val} ]'


def write_atomically(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def from_mitsuba(a, extra):
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import pbrt_from_mitsuba as pm

    if not a.lt_xml:
        fail("a Mitsuba XML scene needs --lt-xml (the copy lt renders)")
    defines = {}
    for kv in a.defines:
        k, eq, v = kv.partition("=")
        if not eq:
            fail(f"-D {kv}: expected KEY=VALUE")
        defines[k] = v
    try:
        pbrt, lt_xml = pm.convert(a.scene, defines, a.integrator, a.spp, a.width, a.exr,
                                  a.sampler, extra, a.ggx_for_beckmann)
    except pm.Refused as e:
        fail(str(e))
    except (ValueError, TypeError, AttributeError) as e:
        fail(f"{a.scene}: a value the converter could not read ({e})")
    write_atomically(a.out, pbrt)
    write_atomically(a.lt_xml, lt_xml)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--integrator", default="path", choices=["path", "bdpt", "mlt", "sppm"])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--width", type=int, default=0)
    ap.add_argument("--exr", default="pbrt.exr")
    ap.add_argument("--sampler", default="zsobol", choices=["zsobol", "independent"])
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("-D", dest="defines", action="append", default=[])
    ap.add_argument("--ggx-for-beckmann", action="store_true")
    ap.add_argument("--lt-xml")
    a = ap.parse_args()
    extra = [integrator_param(kv) for kv in a.set]
    if a.scene.endswith(".xml"):
        return from_mitsuba(a, extra)
    with open(a.scene, "rb") as f:
        s = tomllib.load(f)
    mats = s.get("materials", {})
    for name, mat in mats.items():
        if mat.get("type") != "diffuse":
            fail(f"{a.scene}: material '{name}' is {mat.get('type')}; only diffuse is converted")
    cam = s["camera"]
    w, h = cam.get("resolution", [256, 256])
    if a.width:
        w, h = a.width, round(h * a.width / w)
    fov = float(cam["fov"])
    axis = cam.get("fov_axis", "x")
    # pbrt's fov spans the shorter axis.
    if axis == "x" and w > h:
        fov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * h / w))
    elif axis == "y" and h > w:
        fov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * w / h))
    elif axis not in ("x", "y", "smaller"):
        fail(f"{a.scene}: fov_axis '{axis}' is not converted")
    depth = int(s.get("render", {}).get("max_depth", 8)) - 1
    if depth < 0:
        fail(f"{a.scene}: max_depth must be at least 1")
    params = [f'"integer maxdepth" [ {depth} ]'] + extra
    out = [
        f"# Written by pbrt_scene.py from {a.scene}.\n",
        "Scale -1 1 1\n",
        f'LookAt {nums(cam["eye"])}\n       {nums(cam["target"])}\n       {nums(cam["up"])}\n',
        f'Camera "perspective" "float fov" [ {fov!r} ]\n',
        f'Sampler "{a.sampler}" "integer pixelsamples" [ {a.spp} ]\n',
        'PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]\n',
        f'Film "rgb" "integer xresolution" [ {w} ] "integer yresolution" [ {h} ] '
        f'"string filename" [ "{a.exr}" ]\n',
        f'Integrator "{a.integrator}" {" ".join(params)}\n',
        "WorldBegin\n",
    ]
    for name, mat in mats.items():
        out.append(f'MakeNamedMaterial "{name}" "string type" [ "diffuse" ] '
                   f'"rgb reflectance" [ {nums(mat["albedo"])} ]\n')
    for i, sh in enumerate(s.get("shapes", [])):
        where = f"{a.scene}: shapes[{i}]"
        m = matrix(sh.get("to_world", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), where)
        kind = sh.get("type")
        if kind not in ("quad", "cube"):
            fail(f"{where}: shape type '{kind}' is not converted (quad and cube are)")
        if sh.get("material") not in mats:
            fail(f"{where}: material '{sh.get('material')}' is not defined")
        out.append("AttributeBegin\n")
        out.append(f'  NamedMaterial "{sh["material"]}"\n')
        if "emission" in sh:
            out.append(f'  AreaLightSource "diffuse" "rgb L" [ {nums(sh["emission"])} ]\n')
        out.append("  " + mesh(*(QUAD if kind == "quad" else CUBE), m))
        out.append("AttributeEnd\n")
    write_atomically(a.out, "".join(out))


if __name__ == "__main__":
    main()
