#!/usr/bin/env python3
"""Where an envmap's light subpaths go (results/mitsuba-suite-media.md, `light` on the envmap-lit
scenes): draws N emissions as lt's `light` draws them — a direction by the envmap's luminance
(Mitsuba's own `envmap.sample_direction`), a point on the disk of the scene's bounding sphere
across it — traces each to its first hit and counts the hits a camera sees (in its frustum, facing
it, unoccluded). Also the mean ratio of the disk's area to a rectangle around the scene box
projected across each drawn direction (what a tighter emission domain would gain).

    pip install mitsuba numpy
    python3 crates/experiments/scripts/envmap_emission_reach.py SCENE.xml [N]
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
scene = mi.load_file(sys.argv[1], integrator="path", spp=1)
n = int(sys.argv[2]) if len(sys.argv) > 2 else 20000
env = scene.environment()
lo, hi = np.array(scene.bbox().min), np.array(scene.bbox().max)
centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
sensor = scene.sensors()[0]
eye = np.array(sensor.world_transform().translation())
rng = np.random.default_rng(1)
hit = seen = upward = 0
area_ratio = []
for _ in range(n):
    ds, _w = env.sample_direction(mi.Interaction3f(), mi.Point2f(rng.random(), rng.random()))
    d = -np.array(ds.d)  # light travels away from the envmap
    upward += d[1] > 0
    frame = mi.Frame3f(mi.Vector3f(*d))
    s, t = np.array(frame.s), np.array(frame.t)
    q = mi.warp.square_to_uniform_disk_concentric(mi.Point2f(rng.random(), rng.random()))
    o = centre - d * radius + (s * q[0] + t * q[1]) * radius
    pu, pv = (corners - centre) @ s, (corners - centre) @ t
    area_ratio.append(np.pi * radius**2 / ((pu.max() - pu.min()) * (pv.max() - pv.min())))
    si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o), mi.Vector3f(*d)))
    if not si.is_valid():
        continue
    hit += 1
    p, ng = np.array(si.p), np.array(si.n)
    to_eye = eye - p
    dist = np.linalg.norm(to_eye)
    if np.dot(to_eye, ng) * np.dot(-d, ng) <= 0:
        continue  # lit and seen from different sides
    it = mi.Interaction3f()
    it.p = mi.Point3f(*p)
    sds, _ = sensor.sample_direction(it, mi.Point2f(0.5, 0.5))
    if sds.pdf == 0:
        continue  # outside the frustum
    u = to_eye / dist
    if scene.ray_test(mi.Ray3f(mi.Point3f(*(p + u * 1e-3)), mi.Vector3f(*u), dist * (1 - 2e-3))):
        continue
    seen += 1
print(f"{n} emissions: {hit / n:.1%} hit the scene, {seen / n:.1%} first hit a point the camera sees, "
      f"{upward / n:.1%} travel upwards; disk / projected-box rectangle area: mean "
      f"{np.mean(area_ratio):.2f}, flux-weighted {1 / np.mean(1 / np.array(area_ratio)):.2f}, "
      f"5 % of directions below {np.percentile(area_ratio, 5):.2f}")
