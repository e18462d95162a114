#!/usr/bin/env python3
# Writes scenes/textures/bumps-height.png (8-bit grey heights: three smooth bumps per side) and
# bumps-normal.png (the tangent-space normals of the same bumps, (n+1)/2, to be read raw) for
# scenes/cornell-bumped.toml. Run from the repository root.
import math, struct, zlib
def png(path, w, h, rows, channels):
    color_type = {1: 0, 3: 2}[channels]
    raw = b''.join(b'\x00' + bytes(r) for r in rows)
    def chunk(t, d):
        c = struct.pack('>I', len(d)) + t + d
        return c + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    data = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, color_type, 0, 0, 0)) \
        + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b'')
    open(path, 'wb').write(data)
N = 64
k = 2 * math.pi * 3 / N   # three bumps across the texture
height = lambda x, y: 0.5 + 0.5 * math.sin(k * x) * math.sin(k * y)
rows = [[round(255 * height(x + 0.5, y + 0.5)) for x in range(N)] for y in range(N)]
png('scenes/textures/bumps-height.png', N, N, rows, 1)
# Tangent-space normals of the same bumps at a steeper scale: n ∝ (−s ∂h/∂u, −s ∂h/∂v, 1).
s = 0.04
rows = []
for y in range(N):
    r = []
    for x in range(N):
        hx = 0.5 * k * N * math.cos(k * (x + .5)) * math.sin(k * (y + .5))
        hy = 0.5 * k * N * math.sin(k * (x + .5)) * math.cos(k * (y + .5))
        n = (-s * hx, -s * hy, 1.0)
        l = math.sqrt(sum(c * c for c in n))
        r += [round(255 * (c / l + 1) / 2) for c in n]
    rows.append(r)
png('scenes/textures/bumps-normal.png', N, N, rows, 3)
