#!/usr/bin/env python3
"""Prints the tabulated CIE 1931 2° colour-matching functions and the CIE D65 illuminant that
Mitsuba 3's RGB variants convert `<spectrum>` values with, as the Rust file
crates/scene-io/src/xml/cie_table.rs. Regenerate with

    pip install mitsuba==3.9.1
    python3 crates/experiments/scripts/mitsuba_cie_table.py > crates/scene-io/src/xml/cie_table.rs

Each value is read from Mitsuba (`mi.cie1931_xyz`, `mi.cie_d65`, variant `scalar_rgb`) at every
whole nanometre of 360–830 nm, where its tables have their knots (between knots it interpolates
linearly, as the Rust side does), printed as the shortest literal that reads back as the same f32."""
import struct

import mitsuba as mi

mi.set_variant("scalar_rgb")


def f32(x):
    bits = struct.unpack("<f", struct.pack("<f", float(x)))[0]
    for digits in range(1, 10):
        s = f"{bits:.{digits}g}"
        if struct.unpack("<f", struct.pack("<f", float(s)))[0] == bits:
            break
    return s if ("." in s or "e" in s) else s + ".0"


lo, hi = int(mi.MI_CIE_MIN), int(mi.MI_CIE_MAX)
rows = [mi.cie1931_xyz(float(l)) for l in range(lo, hi + 1)]
d65 = [mi.cie_d65(float(l)) for l in range(lo, hi + 1)]
n = hi - lo + 1
print(f"""//! The CIE 1931 2° colour-matching functions and the CIE D65 illuminant at every whole nanometre
//! of {lo}–{hi} nm, as Mitsuba 3's RGB variants tabulate them (linear between knots). Source:
//! Mitsuba 3.9.1 (`pip install mitsuba==3.9.1`), `mi.cie1931_xyz` and `mi.cie_d65` (D65 scaled
//! by Mitsuba to luminance 1) in `scalar_rgb`; printed by
//! `crates/experiments/scripts/mitsuba_cie_table.py` — regenerate with it, never by hand.

/// First and last wavelength of the tables, nm.
pub(super) const CIE_MIN: f64 = {lo}.0;
pub(super) const CIE_MAX: f64 = {hi}.0;
/// 1 / ∫ ȳ dλ over the table (Mitsuba's `MI_CIE_Y_NORMALIZATION`).
pub(super) const CIE_Y_NORMALIZATION: f64 = {mi.MI_CIE_Y_NORMALIZATION!r};

/// x̄, ȳ, z̄ at CIE_MIN + i nm.
#[rustfmt::skip]
pub(super) const CIE_XYZ: [[f32; 3]; {n}] = [""")
for r in rows:
    print(f"    [{f32(r[0])}, {f32(r[1])}, {f32(r[2])}],")
print(f"""];

/// D65 (luminance-normalised) at CIE_MIN + i nm.
#[rustfmt::skip]
pub(super) const CIE_D65: [f32; {n}] = [""")
for i in range(0, n, 8):
    print("    " + ", ".join(f32(v) for v in d65[i:i + 8]) + ",")
print("];")
