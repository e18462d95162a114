#!/usr/bin/env python3
# Writes scenes/textures/sky-sun.hdr for scenes/envmap-spheres.toml: a 64 × 32 latitude–longitude
# radiance map in Mitsuba's convention (row 0 is the +y pole, u = phi / 2pi with u = 0 towards -z):
# a blue sky brightening to the horizon, a dim brown ground, and a small sun (about 3 texels,
# 2000× the sky) at 35 degrees elevation, so importance sampling decides the noise. Written as flat
# (uncompressed) Radiance RGBE. Run from the repository root.
import math
W, H = 64, 32
def radiance(u, v):
    theta, phi = math.pi * v, 2 * math.pi * u
    d = (math.sin(phi) * math.sin(theta), math.cos(theta), -math.cos(phi) * math.sin(theta))
    if d[1] < 0:
        return (0.25, 0.18, 0.12)
    sky = (0.35 + 0.5 * (1 - d[1]), 0.55 + 0.4 * (1 - d[1]), 1.0)
    el, az = math.radians(35), math.radians(60)
    sun = (math.sin(az) * math.cos(el), math.sin(el), -math.cos(az) * math.cos(el))
    if sum(a * b for a, b in zip(d, sun)) > math.cos(math.radians(4)):
        return (2000.0, 1800.0, 1500.0)
    return sky
def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes([0, 0, 0, 0])
    e = math.frexp(m)[1]
    f = 256.0 / 2 ** e
    return bytes([int(c[0] * f), int(c[1] * f), int(c[2] * f), e + 128])
out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {H} +X {W}\n".encode())
for y in range(H):
    for x in range(W):
        out += rgbe(radiance((x + 0.5) / W, y / (H - 1)))
open("scenes/textures/sky-sun.hdr", "wb").write(bytes(out))
