#!/usr/bin/env python3
"""Writes grid-smoke.vol, the density grid of grid-smoke.xml, deterministically (standard library
only; run from anywhere: `python3 scenes/media/make_grid_smoke.py`).

The grid is the analytic density
    d(p) = exp(-|p - c1|^2 / (2 s1^2)) + 0.6 exp(-|p - c2|^2 / (2 s2^2)),
    c1 = (0.42, 0.40, 0.50), s1 = 0.18,   c2 = (0.68, 0.66, 0.45), s2 = 0.11,
two Gaussian puffs in the unit cube, sampled at the cell centres p = ((i + 1/2)/N, (j + 1/2)/N,
(k + 1/2)/N) of an N = 16 grid (Mitsuba's cell-centred convention, so the trilinear lookup
returns d exactly at those points) and rounded once to float32. The file is Mitsuba's .vol:
"VOL", version 3, encoding 1 (float32), x/y/z resolution, 1 channel, the bounding box [0, 1]^3,
then the values with x fastest, then y, then z, all little-endian.
"""

import math
import os
import struct

N = 16
PUFFS = [((0.42, 0.40, 0.50), 0.18, 1.0), ((0.68, 0.66, 0.45), 0.11, 0.6)]


def density(p):
    total = 0.0
    for c, s, a in PUFFS:
        r2 = sum((p[i] - c[i]) ** 2 for i in range(3))
        total += a * math.exp(-r2 / (2.0 * s * s))
    return total


def main():
    out = bytearray(b"VOL")
    out += struct.pack("<B", 3)
    out += struct.pack("<iiiii", 1, N, N, N, 1)
    out += struct.pack("<6f", 0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
    for k in range(N):
        for j in range(N):
            for i in range(N):
                p = ((i + 0.5) / N, (j + 0.5) / N, (k + 0.5) / N)
                out += struct.pack("<f", density(p))
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "grid-smoke.vol")
    with open(path, "wb") as f:
        f.write(out)
    print(f"wrote {path}: {N}^3 cells, {len(out)} bytes")


if __name__ == "__main__":
    main()
