#!/usr/bin/env python3
"""Prints the RGB complex IORs (eta, k) that Mitsuba 3's RGB variants use for its named conductor
materials (`<bsdf type="conductor"><string name="material" value="Au"/>`), as the Rust table in
crates/core/src/bsdf/conductor_ior.rs. Regenerate with

    pip install mitsuba==3.9.1
    python3 crates/experiments/scripts/mitsuba_conductor_table.py > /tmp/table.rs

and paste the printed rows over the table's rows. Values are read back from a loaded `conductor`
in the `scalar_rgb` variant with `mi.traverse` (Mitsuba turns each tabulated spectrum into RGB when
it loads the material), so they are exactly what Mitsuba renders with, printed as f32 with 9
significant digits (round-trips the bits)."""
import os
import struct

import mitsuba as mi

mi.set_variant("scalar_rgb")
# Mitsuba warns when it clamps an out-of-gamut RGB (k of a few dielectrics); the clamped value is
# what it renders with, and what is printed.
mi.set_log_level(mi.LogLevel.Error)


def f32(x):
    """The shortest literal that reads back as the same f32."""
    bits = struct.unpack("<f", struct.pack("<f", float(x)))[0]
    for digits in range(6, 10):
        s = f"{bits:.{digits}g}"
        if struct.unpack("<f", struct.pack("<f", float(s)))[0] == bits:
            break
    if "." not in s and "e" not in s:
        s += ".0"
    return s


def rgb(v):
    return "[" + ", ".join(f32(v[i]) for i in range(3)) + "]"


ior_dir = os.path.join(os.path.dirname(mi.__file__), "data", "ior")
names = sorted({f.split(".")[0] for f in os.listdir(ior_dir) if f.endswith(".eta.spd")})
print(f"// Mitsuba {mi.__version__}, variant scalar_rgb: {len(names)} materials.")
for name in names:
    if not os.path.exists(os.path.join(ior_dir, name + ".k.spd")):
        continue
    params = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
    eta, k = params["eta.value"], params["k.value"]
    print(f'    ("{name}", {rgb(eta)}, {rgb(k)}),')
