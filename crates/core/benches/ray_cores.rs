//! `cargo bench -p lt-core --features bench --bench ray_cores`: where the flat ray core stops beating the BVH, and
//! (`-- scaling`) the BVH, wide and Embree cores on 10³–10⁶ triangles.
//! Closest hits and occlusion of 100 000 rays from inside a box of N parallelograms (its six
//! walls plus N − 6 random ones inside: the shape of a Cornell box with more furniture), of N/2
//! parallelograms and N/2 spheres, or of N triangles (the walls as triangle pairs), with each
//! core (one thread). `FLAT_MAX_PRIMITIVES` in
//! `geometry/accel.rs` is set from this.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lt_core::geometry::quad::Parallelogram;
use lt_core::geometry::{Accel, Primitive, Ray, RayCore};
use lt_core::Vec3;
use rand_pcg::rand_core::Rng;
use rand_pcg::Pcg32;
use std::hint::black_box;

const RAYS: usize = 100_000;

fn uniform(r: &mut Pcg32) -> f32 {
    (r.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

fn point(r: &mut Pcg32, half: f32) -> Vec3 {
    Vec3::new(uniform(r), uniform(r), uniform(r)) * (2.0 * half) - half
}

fn direction(r: &mut Pcg32) -> Vec3 {
    loop {
        let v = point(r, 1.0);
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Quads,
    QuadsAndSpheres,
    Triangles,
}

/// The walls of [-1, 1]³ and random primitives of size ~0.3 inside, `n` in all: parallelograms,
/// every other one a sphere, or triangles (then the walls are triangle pairs too).
fn scene(n: usize, kind: Kind, seed: u64) -> Vec<Primitive> {
    scene_sized(n, kind, seed, 0.3)
}

/// `scene` with primitives of size `size`.
fn scene_sized(n: usize, kind: Kind, seed: u64, size: f32) -> Vec<Primitive> {
    let mut r = Pcg32::new(seed, 0x5851_f42d_4c95_7f2d);
    let mut prims = Vec::new();
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut p0 = Vec3::splat(-1.0);
            p0[axis] = side;
            let (mut e1, mut e2) = (Vec3::ZERO, Vec3::ZERO);
            e1[u] = 2.0;
            e2[v] = 2.0;
            let shape = prims.len() as u32;
            if kind == Kind::Triangles {
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
    while prims.len() < n {
        let shape = prims.len() as u32;
        let c = point(&mut r, 0.8);
        if kind == Kind::Triangles {
            let (a, b) = (direction(&mut r) * size, direction(&mut r) * size);
            prims.push(Primitive::Triangle {
                p: [c, c + a, c + b],
                shape,
                index: 0,
            });
        } else if kind == Kind::QuadsAndSpheres && shape.is_multiple_of(2) {
            prims.push(Primitive::Sphere {
                center: c,
                radius: 0.05 + 0.1 * uniform(&mut r),
                shape,
            });
        } else {
            let q = Parallelogram::new(c, direction(&mut r) * size, direction(&mut r) * size);
            prims.push(Primitive::Quad { q, shape, index: 0 });
        }
    }
    prims
}

fn rays(seed: u64) -> Vec<Ray> {
    let mut r = Pcg32::new(seed, 7);
    (0..RAYS)
        .map(|_| Ray::new(point(&mut r, 0.9), direction(&mut r)))
        .collect()
}

fn bench(c: &mut Criterion) {
    let rays = rays(2);
    for (kind, name) in [
        (Kind::Quads, "quads"),
        (Kind::QuadsAndSpheres, "quads+spheres"),
        (Kind::Triangles, "triangles"),
    ] {
        let mut group = c.benchmark_group(format!("closest_hit/{name}"));
        group.throughput(Throughput::Elements(RAYS as u64));
        for n in [8, 16, 32, 64, 128, 256] {
            for core in [RayCore::Bvh, RayCore::Flat] {
                let accel = Accel::build_with(scene(n, kind, 1), core);
                group.bench_with_input(BenchmarkId::new(accel.describe(), n), &rays, |b, rays| {
                    b.iter(|| {
                        rays.iter()
                            .filter(|ray| accel.intersect(black_box(ray)).is_some())
                            .count()
                    })
                });
            }
        }
        group.finish();
        let mut group = c.benchmark_group(format!("occluded/{name}"));
        group.throughput(Throughput::Elements(RAYS as u64));
        for n in [8, 16, 32, 64, 128, 256] {
            for core in [RayCore::Bvh, RayCore::Flat] {
                let accel = Accel::build_with(scene(n, kind, 1), core);
                let short: Vec<Ray> = rays.iter().map(|r| Ray { t_max: 0.5, ..*r }).collect();
                group.bench_with_input(BenchmarkId::new(accel.describe(), n), &short, |b, rays| {
                    b.iter(|| {
                        rays.iter()
                            .filter(|ray| accel.occluded(black_box(ray)))
                            .count()
                    })
                });
            }
        }
        group.finish();
    }
}

/// 10³–10⁶ random triangles inside the box, their size shrinking as 1/√n so that their total area
/// (and so what a ray meets) stays that of 1 000 triangles of size 0.3.
fn scaling(c: &mut Criterion) {
    let rays = rays(2);
    let short: Vec<Ray> = rays.iter().map(|r| Ray { t_max: 0.5, ..*r }).collect();
    let cores: Vec<RayCore> = [RayCore::Bvh, RayCore::Embree, RayCore::Wide]
        .into_iter()
        .filter(|c| c.available())
        .collect();
    for n in [1_000, 10_000, 100_000, 1_000_000] {
        let prims = scene_sized(n, Kind::Triangles, 1, 0.3 * (1000.0 / n as f32).sqrt());
        let mut group = c.benchmark_group(format!("scaling/{n}"));
        group.throughput(Throughput::Elements(RAYS as u64));
        group.sample_size(10);
        for &core in &cores {
            let accel = Accel::build_with(prims.clone(), core);
            group.bench_with_input(
                BenchmarkId::new("closest", accel.describe()),
                &rays,
                |b, rays| {
                    b.iter(|| {
                        rays.iter()
                            .filter(|ray| accel.intersect(black_box(ray)).is_some())
                            .count()
                    })
                },
            );
            group.bench_with_input(
                BenchmarkId::new("occluded", accel.describe()),
                &short,
                |b, rays| {
                    b.iter(|| {
                        rays.iter()
                            .filter(|ray| accel.occluded(black_box(ray)))
                            .count()
                    })
                },
            );
        }
        group.finish();
    }
}

criterion_group!(benches, bench, scaling);
criterion_main!(benches);
