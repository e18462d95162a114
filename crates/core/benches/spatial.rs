//! `cargo bench -p lt-core --features bench --bench spatial`: PointGrid against a Vec sorted by cell key (one
//! binary search per row of cells) on photon-like points: 250k on the five walls of a 2×2×2 box,
//! gathered by 1M radius queries of ≈50 neighbours each (one thread).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lt_core::spatial::PointGrid;
use lt_core::Vec3;
use rand_pcg::rand_core::Rng;
use rand_pcg::Pcg32;
use rayon::prelude::*;
use std::hint::black_box;

const POINTS: usize = 250_000;
const QUERIES: usize = 1_000_000;
/// πr² · (250k / 20 units² of wall) ≈ 48 neighbours.
const RADIUS: f32 = 0.035;

fn uniform(r: &mut Pcg32) -> f32 {
    (r.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// A uniform point on the floor, ceiling, back, left or right wall of [-1, 1]³, in random order
/// as photons arrive.
fn on_walls(n: usize, seed: u64) -> Vec<Vec3> {
    let mut r = Pcg32::new(seed, 0x5851_f42d_4c95_7f2d);
    (0..n)
        .map(|_| {
            let wall = r.next_u32() % 5;
            let (u, v) = (uniform(&mut r) * 2.0 - 1.0, uniform(&mut r) * 2.0 - 1.0);
            match wall {
                0 => Vec3::new(u, -1.0, v),
                1 => Vec3::new(u, 1.0, v),
                2 => Vec3::new(u, v, -1.0),
                3 => Vec3::new(-1.0, u, v),
                _ => Vec3::new(1.0, u, v),
            }
        })
        .collect()
}

/// The alternative: indices sorted (in parallel) by a (z, y, x) cell key; a query binary-searches the start
/// of each row of cells it covers and walks the row's run.
struct SortedCells {
    min: Vec3,
    inv_cell: f32,
    keys: Vec<u64>,
    indices: Vec<u32>,
}

impl SortedCells {
    fn cell(&self, p: Vec3) -> [u64; 3] {
        // Truncation is floor once clamped to >= 0 (and avoids a libm call).
        let c = ((p - self.min) * self.inv_cell).max(Vec3::ZERO);
        [c.x as u64, c.y as u64, c.z as u64].map(|c| c.min((1 << 21) - 1))
    }

    fn key(c: [u64; 3]) -> u64 {
        (c[2] << 42) | (c[1] << 21) | c[0]
    }

    fn build(points: &[Vec3], cell: f32) -> SortedCells {
        let min = points.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let mut s = SortedCells {
            min,
            inv_cell: 1.0 / cell,
            keys: Vec::new(),
            indices: Vec::new(),
        };
        let mut pairs: Vec<(u64, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, &p)| (Self::key(s.cell(p)), i as u32))
            .collect();
        pairs.par_sort_unstable();
        s.keys = pairs.iter().map(|e| e.0).collect();
        s.indices = pairs.iter().map(|e| e.1).collect();
        s
    }

    fn for_each_within(&self, points: &[Vec3], q: Vec3, r: f32, mut f: impl FnMut(u32, f32)) {
        let (lo, hi) = (self.cell(q - r), self.cell(q + r));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let (a, b) = (Self::key([lo[0], y, z]), Self::key([hi[0], y, z]));
                let start = self.keys.partition_point(|&k| k < a);
                for j in start..self.keys.len() {
                    if self.keys[j] > b {
                        break;
                    }
                    let i = self.indices[j];
                    let d2 = (points[i as usize] - q).length_squared();
                    if d2 <= r * r {
                        f(i, d2);
                    }
                }
            }
        }
    }
}

fn spatial(c: &mut Criterion) {
    let points = on_walls(POINTS, 1);
    let queries = on_walls(QUERIES, 2);
    let cell = 2.0 * RADIUS;
    let grid = PointGrid::build(&points, cell);
    let sorted = SortedCells::build(&points, cell);
    // Both must find the same neighbours, or the timing compares different work.
    let count = |f: &dyn Fn(Vec3, &mut u64)| {
        let mut n = 0;
        queries[..10_000].iter().for_each(|&q| f(q, &mut n));
        n
    };
    let a = count(&|q, n| grid.for_each_within(&points, q, RADIUS, |_, _| *n += 1));
    let b = count(&|q, n| sorted.for_each_within(&points, q, RADIUS, |_, _| *n += 1));
    assert_eq!(a, b);
    println!("mean neighbours per query: {:.1}", a as f64 / 10_000.0);

    let mut g = c.benchmark_group("spatial_build_250k");
    g.sample_size(20);
    g.bench_function("point_grid", |b| {
        b.iter(|| PointGrid::build(black_box(&points), cell))
    });
    g.bench_function("sorted_cells", |b| {
        b.iter(|| SortedCells::build(black_box(&points), cell))
    });
    g.finish();

    let mut g = c.benchmark_group("spatial_1M_radius_queries");
    g.sample_size(10);
    g.throughput(Throughput::Elements(QUERIES as u64));
    g.bench_function("point_grid", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &q in &queries {
                grid.for_each_within(&points, q, RADIUS, |_, d2| sum += d2);
            }
            sum
        })
    });
    g.bench_function("sorted_cells", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &q in &queries {
                sorted.for_each_within(&points, q, RADIUS, |_, d2| sum += d2);
            }
            sum
        })
    });
    g.finish();

    let mut g = c.benchmark_group("spatial_100k_k_nearest_50");
    g.sample_size(10);
    g.throughput(Throughput::Elements(100_000));
    g.bench_function("point_grid", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            let mut sum = 0.0f32;
            for &q in &queries[..100_000] {
                grid.k_nearest(&points, q, 50, f32::INFINITY, &mut out);
                sum += out.last().map_or(0.0, |e| e.1);
            }
            sum
        })
    });
    g.finish();
}

criterion_group!(benches, spatial);
criterion_main!(benches);
