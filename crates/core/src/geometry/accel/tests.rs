use super::*;
use crate::geometry::flat::Isa;
use crate::geometry::quad::Parallelogram;
use crate::sampling::{sample_uniform_sphere, Sampler};

/// Random triangles, parallelograms, spheres, disks and cylinders at scale `scale`, `n` of them.
fn random_primitives(s: &mut Sampler, n: u32, scale: f32) -> Vec<Primitive> {
    (0..n)
        .map(|i| {
            let c = (s.next_2d().extend(s.next_f32()) - 0.5) * 10.0 * scale;
            let e1 = sample_uniform_sphere(s.next_2d()) * scale;
            let e2 = sample_uniform_sphere(s.next_2d()) * scale;
            // A disk or cylinder: e1, e2 and their normal (length 0.5) as its axes.
            let quadric = || {
                let m = glam::Mat3::from_cols(e1, e2, 0.5 * e1.cross(e2).normalize() * scale);
                crate::geometry::quadric::Affine::new(m, c).inverse()
            };
            match i % 5 {
                3 => Primitive::Disk {
                    to_object: quadric(),
                    shape: i,
                },
                4 => Primitive::Cylinder {
                    to_object: quadric(),
                    shape: i,
                },
                0 => Primitive::Sphere {
                    center: c,
                    radius: (0.3 * s.next_f32() + 0.01) * scale,
                    shape: i,
                },
                1 => Primitive::Triangle {
                    p: [c, c + e1, c + e2],
                    shape: i,
                    index: 0,
                },
                _ => Primitive::Quad {
                    q: Parallelogram::new(c, e1, e2),
                    shape: i,
                    index: 0,
                },
            }
        })
        .collect()
}

/// A closed box of six parallelograms around the origin, a smaller one inside and a third,
/// of triangle pairs, between them: rays aimed at their shared edges and corners hit two faces
/// at exactly the same distance, and make triangle edge functions exactly zero.
fn boxes(scale: f32) -> Vec<Primitive> {
    let mut prims = Vec::new();
    for (half, flip) in [(1.0f32, false), (0.3, true), (0.6, false)] {
        let h = half * scale;
        for axis in 0..3 {
            for side in [-1.0f32, 1.0] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut p0 = Vec3::splat(-h);
                p0[axis] = side * h;
                let (mut e1, mut e2) = (Vec3::ZERO, Vec3::ZERO);
                e1[u] = 2.0 * h;
                e2[v] = 2.0 * h;
                let (e1, e2) = if flip { (e2, e1) } else { (e1, e2) };
                let shape = prims.len() as u32;
                if half == 0.6 {
                    for p in [[p0, p0 + e1, p0 + e1 + e2], [p0, p0 + e1 + e2, p0 + e2]] {
                        prims.push(Primitive::Triangle { p, shape, index: 0 });
                    }
                } else {
                    prims.push(Primitive::Quad {
                        q: Parallelogram::new(p0, e1, e2),
                        shape,
                        index: 0,
                    });
                }
            }
        }
    }
    prims
}

/// Rays from random points and from points on the primitives (short hits near edges and
/// corners), with `at_edges` a quarter of them aimed at the boxes' edges and corners (exact
/// ties); some with a finite t_max.
fn test_rays(
    s: &mut Sampler,
    prims: &[Primitive],
    scale: f32,
    n: usize,
    at_edges: bool,
) -> Vec<Ray> {
    (0..n)
        .map(|k| {
            let o = if k % 3 == 0 {
                (s.next_2d().extend(s.next_f32()) - 0.5) * 1.9 * scale
            } else if k % 3 == 1 {
                (s.next_2d().extend(s.next_f32()) - 0.5) * 12.0 * scale
            } else {
                match prims[k % prims.len()] {
                    Primitive::Triangle { p, .. } => 0.4 * p[0] + 0.3 * p[1] + 0.3 * p[2],
                    Primitive::Quad { q, .. } => q.p0 + 0.3 * q.e1 + 0.6 * q.e2,
                    Primitive::Sphere { center, radius, .. } => center + Vec3::X * radius * 1.001,
                    Primitive::Disk { to_object, .. } | Primitive::Cylinder { to_object, .. } => {
                        to_object.inverse().point(Vec3::new(0.5, 0.5, 0.5))
                    }
                    Primitive::SdfVoxel { voxel, .. } => {
                        voxel.to_voxel.inverse().point(Vec3::splat(0.5))
                    }
                }
            };
            let d = if at_edges && k % 4 == 0 {
                // A box edge or corner: two or three coordinates at ±half, scale 1 or 0.3.
                let half = [1.0, 0.3, 0.6][k / 4 % 3] * scale;
                let mut target = (s.next_2d().extend(s.next_f32()) - 0.5) * 2.0 * half;
                for axis in 0..3 {
                    if s.next_f32() < 0.7 {
                        target[axis] = if s.next_f32() < 0.5 { -half } else { half };
                    }
                }
                (target - o).normalize()
            } else if k % 7 == 3 && k % 3 != 2 {
                // Along an axis, with signed zeros as negating an axis vector gives them (from
                // random origins: from a box face, an axis ray grazes the face's edges).
                [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z][k / 7 % 6]
            } else {
                sample_uniform_sphere(s.next_2d())
            };
            let mut ray = Ray::new(o, d);
            if s.next_f32() < 0.3 {
                ray.t_max = 3.0 * scale * s.next_f32();
            }
            ray
        })
        .filter(|r| r.d.is_finite())
        .collect()
}

/// Every core of `cores` answers each ray exactly as `scalar` does: the same distance and
/// primitive, the same occlusion. Returns how many closest hits were ties between primitives.
fn assert_same_hits(
    scalar: &Accel,
    cores: &[Accel],
    prims: &[Primitive],
    rays: &[Ray],
    scale: f32,
) -> usize {
    let mut ties = 0;
    for ray in rays {
        let b = scalar.intersect(ray);
        for c in cores {
            assert_eq!(
                c.intersect(ray).map(|h| (h.t.to_bits(), h.prim)),
                b.map(|h| (h.t.to_bits(), h.prim)),
                "scale {scale}, ray {ray:?}"
            );
            assert_eq!(c.occluded(ray), scalar.occluded(ray), "ray {ray:?}");
        }
        if let Some(h) = b {
            let r = ShearedRay::new(ray.o, ray.d);
            let at_t = prims
                .iter()
                .filter(|p| p.intersect(&r, ray.o, ray.d, ray.t_max) == h.t)
                .count();
            ties += (at_t > 1) as usize;
        }
    }
    ties
}

/// The vectorised flat test is the scalar one, bit for bit, at every width the CPU runs: the
/// same distance, the same primitive (ties at shared edges included), the same occlusion, at
/// every scale.
#[test]
fn wide_flat_test_is_the_scalar_reference_bit_for_bit() {
    let mut ties = 0;
    for scale in [1e-3f32, 1.0, 1e6] {
        let mut s = Sampler::new(3, scale.to_bits() as u64, 0);
        let mut prims = boxes(scale);
        prims.extend(random_primitives(&mut s, 40, 0.1 * scale));
        let scalar = Accel::build_with(prims.clone(), RayCore::FlatScalar);
        // Every width this CPU runs (AVX-512, AVX2, baseline on the project's machines).
        let wide: Vec<Accel> = Isa::available()
            .into_iter()
            .map(|isa| Accel {
                structure: Structure::Flat(Flat::with_isa(&prims, isa)),
                ..Accel::build_with(prims.clone(), RayCore::FlatScalar)
            })
            .collect();
        assert_eq!(
            Accel::build_with(prims.clone(), RayCore::Flat).core(),
            RayCore::Flat
        );
        assert_eq!(scalar.core(), RayCore::FlatScalar);
        let rays = test_rays(&mut s, &prims, scale, 20_000, true);
        ties += assert_same_hits(&scalar, &wide, &prims, &rays, scale);
    }
    // The edge- and corner-aimed rays must actually exercise the tie-break.
    assert!(ties > 100, "only {ties} ties");
}

/// The packet queries (`packet.rs`) answer each active ray of a packet exactly as the
/// single-ray scalar reference does — distance bits and primitive, ties at shared edges
/// included; occluded or not — and inactive rays with `None` (not occluded), at every width
/// the CPU runs and every scale, on boxes alone (parallelograms only) and with spheres,
/// triangles and disks added.
#[test]
fn packet_query_is_the_single_ray_query_bit_for_bit() {
    let mut ties = 0;
    // Active rays the scalar query finds open and blocked.
    let mut open_blocked = [0usize; 2];
    for (scale, extra) in [(1e-3f32, 40), (1.0, 0), (1.0, 40), (1e6, 40)] {
        let mut s = Sampler::new(17, scale.to_bits() as u64 + extra, 0);
        let mut prims = boxes(scale);
        prims.extend(random_primitives(&mut s, extra as u32, 0.1 * scale));
        let scalar = Accel::build_with(prims.clone(), RayCore::FlatScalar);
        let mut cores: Vec<Accel> = Isa::available()
            .into_iter()
            .map(|isa| Accel {
                structure: Structure::Flat(Flat::with_isa(&prims, isa)),
                ..Accel::build_with(prims.clone(), RayCore::FlatScalar)
            })
            .collect();
        cores.push(Accel::build_with(prims.clone(), RayCore::Wide));
        let rays = test_rays(&mut s, &prims, scale, 8000, true);
        for packet in rays.chunks_exact(PACKET) {
            let rays: [Ray; PACKET] = std::array::from_fn(|i| packet[i]);
            let active: [bool; PACKET] = std::array::from_fn(|_| s.next_f32() < 0.8);
            let expected: [_; PACKET] = std::array::from_fn(|i| {
                let h = active[i].then(|| scalar.intersect(&rays[i])).flatten();
                h.map(|h| (h.t.to_bits(), h.prim))
            });
            let blocked: [bool; PACKET] =
                std::array::from_fn(|i| active[i] && scalar.occluded(&rays[i]));
            for b in blocked.iter().zip(&active).filter(|(_, &a)| a) {
                open_blocked[*b.0 as usize] += 1;
            }
            for c in &cores {
                let got = c.intersect_packet(&rays, &active);
                let got = got.map(|h| h.map(|h| (h.t.to_bits(), h.prim)));
                assert_eq!(
                    got, expected,
                    "scale {scale}, rays {rays:?}, active {active:?}"
                );
                assert_eq!(
                    c.occluded_packet(&rays, &active),
                    blocked,
                    "occlusion: scale {scale}, rays {rays:?}, active {active:?}"
                );
            }
        }
        ties += assert_same_hits(&scalar, &[], &prims, &rays, scale);
    }
    assert!(ties > 100, "only {ties} ties");
    // Both answers of the occlusion query must be exercised, each many times.
    assert!(open_blocked.iter().all(|&n| n > 1000), "{open_blocked:?}");
}

/// The wide BVH gives the scalar reference's answer bit for bit at every width the CPU runs:
/// the same distance and primitive (ties at shared edges and corners, grazing hits at box
/// edges included) and the same occlusion, at scales 1e-3 to 1e6, on a scene deep enough for
/// several levels of wide nodes.
#[test]
fn wide_bvh_is_the_scalar_reference_bit_for_bit() {
    let mut ties = 0;
    for scale in [1e-3f32, 1.0, 1e6] {
        let mut s = Sampler::new(13, scale.to_bits() as u64, 0);
        let mut prims = boxes(scale);
        prims.extend(random_primitives(&mut s, 600, 0.3 * scale));
        let scalar = Accel::build_with(prims.clone(), RayCore::FlatScalar);
        let wide: Vec<Accel> = Isa::available()
            .into_iter()
            .filter(|&isa| isa <= Isa::Avx2)
            .map(|isa| Accel {
                structure: Structure::Wide(WideBvh::with_isa(&prims, isa)),
                ..Accel::build_with(prims.clone(), RayCore::FlatScalar)
            })
            .collect();
        assert_eq!(
            Accel::build_with(prims.clone(), RayCore::Wide).core(),
            RayCore::Wide
        );
        let rays = test_rays(&mut s, &prims, scale, 6000, true);
        ties += assert_same_hits(&scalar, &wide, &prims, &rays, scale);
    }
    assert!(ties > 30, "only {ties} ties");
}

/// The BVH finds the same closest distance as testing every primitive (within the rounding of
/// its traversal back-off) and reports a primitive that is hit at that distance. Not for rays
/// aimed exactly at a box's edge or corner: there the primitive tests, widened by their
/// rounding bound, accept a grazing hit that obvhs's node test may round away (seen at a
/// corner of the outer box, scale 1), which the flat cores, having no node tests, never do.
fn bvh_agrees_with_every_primitive_at(scale: f32) {
    let mut s = Sampler::new(1, scale.to_bits() as u64, 0);
    let mut prims = boxes(scale);
    prims.extend(random_primitives(&mut s, 200, scale));
    let accel = Accel::build_with(prims.clone(), RayCore::Bvh);
    assert_eq!(accel.core(), RayCore::Bvh);
    for ray in test_rays(&mut s, &prims, scale, 4000, false) {
        let r = ShearedRay::new(ray.o, ray.d);
        let expected = flat::closest_scalar(&prims, &ray, &r).map_or(f32::INFINITY, |h| h.t);
        match accel.intersect(&ray) {
            Some(h) => {
                let tol = 2.0 * f32::EPSILON * (expected + TRAVERSAL_BACKOFF);
                assert!(
                    (h.t - expected).abs() <= tol,
                    "scale {scale}: {} vs {expected}, ray {ray:?}, expected {:?}, got {:?}",
                    h.t,
                    flat::closest_scalar(&prims, &ray, &r).map(|h| prims[h.prim as usize]),
                    accel.primitive(h.prim)
                );
                let p = accel.primitive(h.prim);
                assert_eq!(p.intersect(&r, ray.o, ray.d, ray.t_max), h.t);
            }
            None => assert!(
                expected.is_infinite(),
                "scale {scale}: BVH missed a hit at {expected}, ray {ray:?}"
            ),
        }
        assert_eq!(accel.occluded(&ray), expected.is_finite());
    }
}

/// Embree names a primitive that lt's own test hits, at lt's own distance to it, which is the
/// closest distance of all primitives up to the rounding of two different triangle tests; it
/// loses no hit and finds the same occlusion.
#[cfg(lt_embree)]
#[test]
fn embree_agrees_with_every_primitive_at_every_scale() {
    for scale in [1e-3f32, 1.0, 1e6] {
        let mut s = Sampler::new(7, scale.to_bits() as u64, 0);
        let mut prims = boxes(scale);
        prims.extend(random_primitives(&mut s, 200, scale));
        let accel = Accel::build_with(prims.clone(), RayCore::Embree);
        assert_eq!(accel.core(), RayCore::Embree);
        for ray in test_rays(&mut s, &prims, scale, 4000, false) {
            let r = ShearedRay::new(ray.o, ray.d);
            let expected = flat::closest_scalar(&prims, &ray, &r).map_or(f32::INFINITY, |h| h.t);
            match accel.intersect(&ray) {
                Some(h) => {
                    let p = accel.primitive(h.prim);
                    assert_eq!(p.intersect(&r, ray.o, ray.d, ray.t_max), h.t);
                    assert!(
                        (h.t - expected).abs() <= 4.0 * f32::EPSILON * expected,
                        "scale {scale}: {} vs {expected}, ray {ray:?}",
                        h.t
                    );
                }
                None => assert!(
                    expected.is_infinite(),
                    "scale {scale}: Embree missed a hit at {expected}, ray {ray:?}"
                ),
            }
            assert_eq!(accel.occluded(&ray), expected.is_finite(), "ray {ray:?}");
        }
    }
}

#[test]
fn bvh_agrees_with_every_primitive_at_every_scale() {
    for scale in [1e-3, 1.0, 1e6] {
        bvh_agrees_with_every_primitive_at(scale);
    }
}

#[test]
fn auto_picks_flat_for_small_scenes_without_triangles_and_a_tree_otherwise() {
    let mut s = Sampler::new(5, 0, 0);
    let few = random_primitives(&mut s, FLAT_MAX_PRIMITIVES as u32, 1.0);
    let many = random_primitives(&mut s, FLAT_MAX_PRIMITIVES as u32 + 1, 1.0);
    let tree = if Isa::widest() >= Isa::Avx2 {
        RayCore::Wide
    } else {
        RayCore::Bvh
    };
    assert_eq!(Accel::build_with(few.clone(), RayCore::Auto).core(), tree);
    let no_triangles: Vec<Primitive> = few
        .into_iter()
        .filter(|p| !matches!(p, Primitive::Triangle { .. }))
        .collect();
    assert_eq!(
        Accel::build_with(no_triangles, RayCore::Auto).core(),
        RayCore::Flat
    );
    assert_eq!(Accel::build_with(many, RayCore::Auto).core(), tree);
    assert_eq!(
        Accel::build_with(Vec::new(), RayCore::Flat)
            .intersect(&Ray::new(Vec3::ZERO, Vec3::X))
            .map(|h| h.t),
        None
    );
}

/// The small traversal stack and obvhs's full-size one visit the same nodes in the same
/// order, so closest hits and occlusion agree bit for bit.
#[test]
fn small_and_full_traversal_stacks_agree() {
    let mut s = Sampler::new(2, 0, 0);
    let prims: Vec<Primitive> = (0..300u32)
        .map(|i| {
            let c = (s.next_2d().extend(s.next_f32()) - 0.5) * 10.0;
            let e1 = sample_uniform_sphere(s.next_2d());
            let e2 = sample_uniform_sphere(s.next_2d());
            Primitive::Quad {
                q: Parallelogram::new(c, e1, e2),
                shape: i,
                index: 0,
            }
        })
        .collect();
    let accel = Accel::build_with(prims, RayCore::Bvh);
    let Structure::Bvh { bvh, shallow } = &accel.structure else {
        panic!("not a BVH")
    };
    assert!(*shallow, "depth {}", tree_depth(bvh, 0));
    for _ in 0..4000 {
        let o = (s.next_2d().extend(s.next_f32()) - 0.5) * 12.0;
        let mut ray = Ray::new(o, sample_uniform_sphere(s.next_2d()));
        if s.next_f32() < 0.5 {
            ray.t_max = 4.0 * s.next_f32();
        }
        let (a, b) = (
            accel.closest::<SMALL_STACK>(bvh, &ray),
            accel.closest::<FULL_STACK>(bvh, &ray),
        );
        assert_eq!(
            a.map(|h| (h.t.to_bits(), h.prim)),
            b.map(|h| (h.t.to_bits(), h.prim))
        );
        assert_eq!(
            accel.any_hit::<SMALL_STACK>(bvh, &ray),
            accel.any_hit::<FULL_STACK>(bvh, &ray)
        );
    }
}
