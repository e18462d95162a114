"""The Mitsuba 3 XML subset of Bitterli's `veach-bidir` (and scenes like it) as a pbrt-v4 scene,
for pbrt_scene.py: a perspective sensor given by a to_world matrix, hdrfilm with a box or tent
filter, `diffuse` / `twosided` / `dielectric` / `roughconductor` BSDFs referenced by id, `obj` and
`rectangle` shapes, `area` emitters. Anything else is refused with its place in the file.

Conventions beyond pbrt_scene.py's (read from pbrt-v4's and Mitsuba 3's documentation):
- Mitsuba's to_world for a sensor is a look-at frame: columns (left, up, forward, origin), so
  the same LookAt (origin, origin + forward, up) under `Scale -1 1 1` as our TOML cameras.
- Mitsuba's `tent` filter has radius 1 pixel: pbrt's `triangle` with xradius = yradius = 1.
- pbrt-v4's conductor has only the Trowbridge–Reitz (GGX) distribution: a Beckmann
  `roughconductor` is refused unless --ggx-for-beckmann is given, and then the caller must render
  lt's side with GGX too (pbrt_scene.py writes that variant of the XML beside the pbrt file).
- `alpha` is pbrt's roughness with remaproughness false; `twosided` is dropped (pbrt's diffuse
  and conductor BSDFs answer on both sides); `face_normals` true drops the OBJ's normals.
- Mitsuba's `max_depth` counts segments as ours does, so pbrt's maxdepth is one less.
"""
import math
import os
import re
import xml.etree.ElementTree as ET


class Refused(Exception):
    pass


def _floats(text, where, n=None):
    try:
        v = [float(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise Refused(f"{where}: '{text}' is not a list of numbers")
    if n is not None and len(v) != n:
        raise Refused(f"{where}: expected {n} numbers, got {len(v)}")
    return v


class _Params:
    """A Mitsuba element's `$name` defaults, with -D style overrides."""

    def __init__(self, root, defines):
        self.values = {d.get("name"): d.get("value") for d in root.findall("default")}
        self.values.update(defines)

    def sub(self, text):
        for k, v in self.values.items():
            text = text.replace(f"${k}", v)
        if "$" in text:
            raise Refused(f"undefined parameter in '{text}'")
        return text


def _child(el, tag, name, params):
    for c in el.findall(tag):
        if c.get("name") == name:
            return params.sub(c.get("value"))
    return None


def _matrix(el, where, params):
    t = [c for c in el.findall("transform") if c.get("name") == "to_world"]
    if not t:
        return [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    ms = t[0].findall("matrix")
    if len(ms) != 1 or len(list(t[0])) != 1:
        raise Refused(f"{where}: only a to_world given as one <matrix> is converted")
    v = _floats(params.sub(ms[0].get("value")), where, 16)
    return [v[0:4], v[4:8], v[8:12], v[12:16]]


def _apply(m, p):
    return [sum(m[i][j] * p[j] for j in range(3)) + m[i][3] for i in range(3)]


def _normal(m, n):
    # Normals transform by the inverse transpose; for a rigid or uniformly scaled frame the
    # linear part itself does, up to length. The scenes converted use identity OBJ transforms.
    v = [sum(m[i][j] * n[j] for j in range(3)) for i in range(3)]
    length = math.sqrt(sum(x * x for x in v)) or 1.0
    return [x / length for x in v]


def _bsdf(el, where, params, ggx_for_beckmann):
    kind = el.get("type")
    if kind == "twosided":
        inner = el.findall("bsdf")
        if len(inner) != 1:
            raise Refused(f"{where}: twosided must hold one bsdf")
        return _bsdf(inner[0], where, params, ggx_for_beckmann)
    if kind == "diffuse":
        rgb = _child(el, "rgb", "reflectance", params) or "0.5"
        r = _floats(rgb, where)
        r = r * 3 if len(r) == 1 else r
        return f'"string type" [ "diffuse" ] "rgb reflectance" [ {" ".join(map(repr, r))} ]'
    if kind == "dielectric":
        ior_in = float(_child(el, "float", "int_ior", params) or 1.5046)
        ior_out = float(_child(el, "float", "ext_ior", params) or 1.000277)
        return f'"string type" [ "dielectric" ] "float eta" [ {ior_in / ior_out!r} ]'
    if kind == "roughconductor":
        dist = _child(el, "string", "distribution", params) or "beckmann"
        if dist != "ggx" and not ggx_for_beckmann:
            raise Refused(f"{where}: pbrt-v4's conductor is GGX only; this one is {dist} "
                          "(--ggx-for-beckmann renders both sides with GGX)")
        alpha = float(_child(el, "float", "alpha", params) or 0.1)
        spec = _child(el, "rgb", "specular_reflectance", params)
        if spec is not None and _floats(spec, where) not in ([1.0], [1.0, 1.0, 1.0]):
            raise Refused(f"{where}: a specular_reflectance other than 1 is not converted")
        eta = _child(el, "rgb", "eta", params)
        k = _child(el, "rgb", "k", params)
        if eta is None or k is None:
            raise Refused(f"{where}: a roughconductor needs rgb eta and k here")
        return ('"string type" [ "conductor" ] '
                f'"rgb eta" [ {" ".join(map(repr, _floats(eta, where, 3)))} ] '
                f'"rgb k" [ {" ".join(map(repr, _floats(k, where, 3)))} ] '
                f'"float roughness" [ {alpha!r} ] "bool remaproughness" false')
    raise Refused(f"{where}: bsdf type '{kind}' is not converted")


def _obj(path, where):
    ps, ns, uvs, tris = [], [], [], []
    try:
        lines = open(path).read().splitlines()
    except OSError as e:
        raise Refused(f"{where}: cannot read {path}: {e.strerror}")
    for ln, line in enumerate(lines, 1):
        f = line.split()
        if not f:
            continue
        if f[0] == "v":
            ps.append(_floats(" ".join(f[1:4]), f"{path}:{ln}", 3))
        elif f[0] == "vn":
            ns.append(_floats(" ".join(f[1:4]), f"{path}:{ln}", 3))
        elif f[0] == "vt":
            uvs.append(_floats(" ".join(f[1:3]), f"{path}:{ln}", 2))
        elif f[0] == "f":
            corners = []
            for c in f[1:]:
                idx = (c.split("/") + ["", ""])[:3]
                corners.append(tuple(int(x) - 1 if x else -1 for x in idx))
            for i in range(1, len(corners) - 1):
                tris.append((corners[0], corners[i], corners[i + 1]))
    return ps, ns, uvs, tris


def _mesh(ps, ns, uvs, tris, m, face_normals):
    # One pbrt vertex per distinct (position, uv, normal) corner.
    key_of, P, N, UV, idx = {}, [], [], [], []
    for tri in tris:
        for c in tri:
            k = c if not face_normals else (c[0], c[1], -1)
            if k not in key_of:
                key_of[k] = len(P) // 3
                P.extend(_apply(m, ps[k[0]]))
                if k[1] >= 0 and uvs:
                    UV.extend(uvs[k[1]])
                if k[2] >= 0 and ns:
                    N.extend(_normal(m, ns[k[2]]))
            idx.append(key_of[k])
    out = (f'Shape "trianglemesh" "integer indices" [ {" ".join(map(str, idx))} ]\n'
           f'    "point3 P" [ {" ".join(map(repr, P))} ]\n')
    if N and len(N) == len(P):
        out += f'    "normal N" [ {" ".join(map(repr, N))} ]\n'
    if UV and len(UV) * 3 == len(P) * 2:
        out += f'    "point2 uv" [ {" ".join(map(repr, UV))} ]\n'
    return out


def convert(path, defines, integrator, spp, width, exr, sampler, extra, ggx_for_beckmann):
    """The pbrt-v4 scene text for the Mitsuba XML at `path`, and the XML text lt should render
    (the same file, or its GGX variant)."""
    try:
        src = open(path).read()
        root = ET.fromstring(src)
    except OSError as e:
        raise Refused(f"{path}: cannot read: {e.strerror}")
    except ET.ParseError as e:
        raise Refused(f"{path}:{e.position[0]}: not well-formed XML ({e})")
    params = _Params(root, defines)
    base = os.path.dirname(os.path.abspath(path))
    sensors = root.findall("sensor")
    if len(sensors) != 1 or sensors[0].get("type") != "perspective":
        raise Refused(f"{path}: one perspective sensor is converted")
    sensor = sensors[0]
    m = _matrix(sensor, f"{path}: sensor", params)
    eye = [m[i][3] for i in range(3)]
    fwd = [m[i][2] for i in range(3)]
    up = [m[i][1] for i in range(3)]
    film = sensor.find("film")
    w = int(_child(film, "integer", "width", params) or 768)
    h = int(_child(film, "integer", "height", params) or 576)
    if width:
        w, h = width, round(h * width / w)
    fov = float(_child(sensor, "float", "fov", params))
    axis = _child(sensor, "string", "fov_axis", params) or "x"
    if axis == "x" and w > h:
        fov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * h / w))
    elif axis == "y" and h > w:
        fov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * w / h))
    elif axis not in ("x", "y", "smaller"):
        raise Refused(f"{path}: fov_axis '{axis}' is not converted")
    rf = film.find("rfilter")
    rtype = rf.get("type") if rf is not None else "gaussian"
    if rtype == "tent":
        pfilter = 'PixelFilter "triangle" "float xradius" [ 1 ] "float yradius" [ 1 ]'
    elif rtype == "box":
        pfilter = 'PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]'
    else:
        raise Refused(f"{path}: rfilter '{rtype}' is not converted (box, tent are)")
    integ = root.find("integrator")
    depth = int(_child(integ, "integer", "max_depth", params) or -1) if integ is not None else -1
    if depth < 1:
        raise Refused(f"{path}: a finite max_depth ≥ 1 is needed")
    ips = [f'"integer maxdepth" [ {depth - 1} ]'] + extra
    out = [
        f"# Written by pbrt_scene.py from {path}.\n",
        "Scale -1 1 1\n",
        f"LookAt {' '.join(map(repr, eye))}\n"
        f"       {' '.join(repr(e + f) for e, f in zip(eye, fwd))}\n"
        f"       {' '.join(map(repr, up))}\n",
        f'Camera "perspective" "float fov" [ {fov!r} ]\n',
        f'Sampler "{sampler}" "integer pixelsamples" [ {spp} ]\n',
        pfilter + "\n",
        f'Film "rgb" "integer xresolution" [ {w} ] "integer yresolution" [ {h} ] '
        f'"string filename" [ "{exr}" ]\n',
        f'Integrator "{integrator}" {" ".join(ips)}\n',
        "WorldBegin\n",
    ]
    for b in root.findall("bsdf"):
        bid = b.get("id")
        material = _bsdf(b, f"{path}: bsdf {bid}", params, ggx_for_beckmann)
        out.append(f'MakeNamedMaterial "{bid}" {material}\n')
    quad = ([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [0, 1, 2, 0, 2, 3])
    for i, sh in enumerate(root.findall("shape")):
        where = f"{path}: shape {sh.get('id') or i}"
        refs = sh.findall("ref")
        if len(refs) != 1 or sh.find("bsdf") is not None:
            raise Refused(f"{where}: exactly one <ref> to a bsdf is converted")
        out.append("AttributeBegin\n")
        out.append(f'  NamedMaterial "{refs[0].get("id")}"\n')
        em = sh.find("emitter")
        if em is not None:
            if em.get("type") != "area":
                raise Refused(f"{where}: emitter '{em.get('type')}' is not converted")
            L = _floats(_child(em, "rgb", "radiance", params), where, 3)
            out.append(f'  AreaLightSource "diffuse" "rgb L" [ {" ".join(map(repr, L))} ]\n')
        m = _matrix(sh, where, params)
        kind = sh.get("type")
        if kind == "rectangle":
            pts, idx = quad
            P = [c for p in pts for c in _apply(m, p)]
            out.append(f'  Shape "trianglemesh" "integer indices" [ {" ".join(map(str, idx))} ]\n'
                       f'    "point3 P" [ {" ".join(map(repr, P))} ]\n')
        elif kind == "obj":
            fn = os.path.join(base, _child(sh, "string", "filename", params))
            face = (_child(sh, "boolean", "face_normals", params) or "false") == "true"
            out.append("  " + _mesh(*_obj(fn, where), m, face))
        else:
            raise Refused(f"{where}: shape type '{kind}' is not converted (obj, rectangle are)")
        out.append("AttributeEnd\n")
    # lt's copy of the scene may be written elsewhere: its file names made absolute.
    lt_xml = re.sub(r'(<string name="filename" value=")([^"/][^"]*)"',
                    lambda g: f'{g.group(1)}{os.path.join(base, g.group(2))}"', src)
    if ggx_for_beckmann:
        lt_xml = lt_xml.replace('value="beckmann"', 'value="ggx"')
    return "".join(out), lt_xml
