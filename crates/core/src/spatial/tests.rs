//! PointGrid against brute force: exact neighbour sets, k-nearest lists, and thread-count
//! independence.

use super::*;
use rand_pcg::rand_core::Rng;
use rand_pcg::Pcg32;

fn rng(seed: u64) -> Pcg32 {
    Pcg32::new(seed, 0xda3e_39cb_94b9_5bdb)
}

fn uniform(r: &mut Pcg32) -> f32 {
    (r.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

fn in_box(r: &mut Pcg32, lo: Vec3, hi: Vec3) -> Vec3 {
    lo + (hi - lo) * Vec3::new(uniform(r), uniform(r), uniform(r))
}

fn random_points(seed: u64, n: usize, lo: Vec3, hi: Vec3) -> Vec<Vec3> {
    let mut r = rng(seed);
    (0..n).map(|_| in_box(&mut r, lo, hi)).collect()
}

/// Same test as the grid's: the brute-force answer is the definition.
fn brute_within(points: &[Vec3], q: Vec3, r: f32) -> Vec<u32> {
    (0..points.len() as u32)
        .filter(|&i| (points[i as usize] - q).length_squared() <= r * r)
        .collect()
}

/// Asserts the grid reports exactly the brute-force set, each once, with the exact d².
/// Returns how many it found, so callers can check the case was not vacuous.
fn check_within(grid: &PointGrid, points: &[Vec3], q: Vec3, r: f32) -> usize {
    let mut got = Vec::new();
    grid.for_each_within(points, q, r, |i, d2| got.push((i, d2)));
    for &(i, d2) in &got {
        assert_eq!(d2, (points[i as usize] - q).length_squared());
    }
    let mut idx: Vec<u32> = got.iter().map(|e| e.0).collect();
    idx.sort_unstable();
    // The brute-force list is sorted and duplicate-free, so equality also rules out repeats.
    assert_eq!(idx, brute_within(points, q, r), "q = {q:?}, r = {r}");
    idx.len()
}

fn brute_knn(points: &[Vec3], q: Vec3, k: usize, max_r: f32) -> Vec<(u32, f32)> {
    let mut all: Vec<(u32, f32)> = (0..points.len() as u32)
        .map(|i| (i, (points[i as usize] - q).length_squared()))
        .filter(|&(_, d2)| d2 <= max_r * max_r)
        .collect();
    all.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    all.truncate(k);
    all
}

fn check_knn(grid: &PointGrid, points: &[Vec3], q: Vec3, k: usize, max_r: f32) {
    let mut out = vec![(7, 7.0)]; // must be cleared
    grid.k_nearest(points, q, k, max_r, &mut out);
    assert_eq!(
        out,
        brute_knn(points, q, k, max_r),
        "q = {q:?}, k = {k}, max_r = {max_r}"
    );
}

#[test]
fn within_matches_brute_force_on_uniform_points() {
    let points = random_points(1, 2000, Vec3::ZERO, Vec3::ONE);
    let grid = PointGrid::build(&points, 0.1);
    assert_eq!(grid.len(), 2000);
    assert_eq!(grid.cell_size(), 0.1);
    let mut r = rng(2);
    // Smaller than, equal to and larger than the cell, and zero.
    for radius in [0.0, 0.03, 0.1, 0.25, 0.7] {
        let mut found = 0;
        for _ in 0..150 {
            let q = in_box(&mut r, Vec3::splat(-0.2), Vec3::splat(1.2));
            found += check_within(&grid, &points, q, radius);
        }
        assert!(radius == 0.0 || found > 0, "radius {radius}: none found");
    }
    // Queries at the points themselves, where r = 0 must find the point.
    for i in (0..2000).step_by(97) {
        assert!(check_within(&grid, &points, points[i], 0.0) >= 1);
        check_within(&grid, &points, points[i], 0.1);
    }
}

#[test]
fn within_is_exact_on_cell_boundaries() {
    // Cell 0.25 makes every lattice coordinate and distance exact; cell 0.1 makes them round.
    for cell in [0.25f32, 0.1] {
        let mut points = Vec::new();
        for z in 0..9 {
            for y in 0..9 {
                for x in 0..9 {
                    points.push(Vec3::new(x as f32, y as f32, z as f32) * cell);
                }
            }
        }
        let grid = PointGrid::build(&points, cell);
        let radii = [
            0.0,
            0.5,
            1.0,
            2.0,
            std::f32::consts::SQRT_2,
            3f32.sqrt(),
            3.0,
        ]
        .map(|m| m * cell);
        let mut on_boundary = 0;
        for (j, &q) in points.iter().enumerate().step_by(13) {
            for &r in &radii {
                let n = check_within(&grid, &points, q, r);
                // From a lattice point, r = one cell reaches the six face neighbours exactly
                // on the sphere: all must be found when the lattice is exact.
                if cell == 0.25 && r == cell && n == 7 {
                    on_boundary += 1;
                }
            }
            // Mid-face and cell-corner queries.
            let mid = q + Vec3::new(0.5, 0.0, 0.0) * cell;
            check_within(&grid, &points, mid, 0.5 * cell);
            check_within(&grid, &points, mid, 1.5 * cell);
            check_within(&grid, &points, q - Vec3::splat(0.5 * cell), cell);
            let _ = j;
        }
        if cell == 0.25 {
            assert!(
                on_boundary > 0,
                "no interior lattice query saw all six neighbours"
            );
        }
    }
}

#[test]
fn within_handles_duplicates() {
    let p = Vec3::new(0.3, -0.2, 0.7);
    // All identical: the box is a single point and the grid a single cell.
    let same = vec![p; 500];
    let grid = PointGrid::build(&same, 0.05);
    assert_eq!(check_within(&grid, &same, p, 0.0), 500);
    assert_eq!(check_within(&grid, &same, p + Vec3::X * 0.01, 0.01), 500);
    assert_eq!(check_within(&grid, &same, p + Vec3::X * 0.2, 0.1), 0);
    // Duplicates among other points.
    let mut points = random_points(3, 500, Vec3::splat(-1.0), Vec3::ONE);
    for i in 0..300 {
        points.insert(i * 2, p);
    }
    let grid = PointGrid::build(&points, 0.1);
    assert!(check_within(&grid, &points, p, 0.0) >= 300);
    for r in [0.05, 0.1, 0.3] {
        assert!(check_within(&grid, &points, p, r) >= 300);
    }
}

#[test]
fn within_handles_clustered_points() {
    let mut r = rng(4);
    let mut points = Vec::new();
    for _ in 0..5 {
        let c = in_box(&mut r, Vec3::ZERO, Vec3::splat(10.0));
        for _ in 0..400 {
            points.push(c + in_box(&mut r, Vec3::splat(-1e-3), Vec3::splat(1e-3)));
        }
    }
    // Tiny cells leave most of the (large) grid empty; unit cells put a cluster in one or two.
    for cell in [0.01, 1.0] {
        let grid = PointGrid::build(&points, cell);
        for radius in [1e-3, 0.01, 0.5, 5.0] {
            let mut found = 0;
            for i in (0..points.len()).step_by(41) {
                found += check_within(&grid, &points, points[i] + Vec3::splat(5e-4), radius);
            }
            assert!(found > 0);
        }
    }
}

#[test]
fn within_far_from_origin() {
    // At 1e4 an f32 ulp is ~1e-3, so rounding in the cell and distance maths is visible.
    for offset in [Vec3::splat(1e4), Vec3::new(-1e4, 3e3, 1e4)] {
        let points = random_points(5, 2000, offset, offset + Vec3::ONE);
        let grid = PointGrid::build(&points, 0.05);
        let mut r = rng(6);
        for radius in [0.003, 0.05, 0.2] {
            let mut found = 0;
            for _ in 0..100 {
                let q = in_box(&mut r, offset, offset + Vec3::ONE);
                found += check_within(&grid, &points, q, radius);
            }
            for i in (0..2000).step_by(101) {
                found += check_within(&grid, &points, points[i], radius);
            }
            assert!(found > 0);
        }
    }
}

#[test]
fn within_query_far_outside_the_box() {
    let points = random_points(7, 1000, Vec3::ZERO, Vec3::ONE);
    let grid = PointGrid::build(&points, 0.1);
    for q in [
        Vec3::splat(1e3),
        Vec3::new(-50.0, 0.5, 0.5),
        Vec3::new(0.5, 0.5, -1e9),
    ] {
        assert_eq!(check_within(&grid, &points, q, 0.3), 0);
    }
    // Reaching into the box from outside: one face's slab.
    assert!(check_within(&grid, &points, Vec3::new(-50.0, 0.5, 0.5), 50.2) > 0);
    assert_eq!(
        check_within(&grid, &points, Vec3::splat(1e3), f32::INFINITY),
        1000
    );
    assert_eq!(check_within(&grid, &points, Vec3::splat(0.5), 1e30), 1000);
}

#[test]
fn empty_and_single_point() {
    let grid = PointGrid::build(&[], 1.0);
    assert!(grid.is_empty());
    assert_eq!(grid.len(), 0);
    grid.for_each_within(&[], Vec3::ZERO, f32::INFINITY, |_, _| panic!("empty grid"));
    let mut out = vec![(0, 0.0)];
    grid.k_nearest(&[], Vec3::ZERO, 3, f32::INFINITY, &mut out);
    assert!(out.is_empty());

    let one = [Vec3::new(2.0, -3.0, 4.0)];
    let grid = PointGrid::build(&one, 0.5);
    assert_eq!(check_within(&grid, &one, one[0], 0.0), 1);
    assert_eq!(check_within(&grid, &one, Vec3::ZERO, 1.0), 0);
    assert_eq!(check_within(&grid, &one, Vec3::ZERO, 10.0), 1);
    for k in [0, 1, 4] {
        check_knn(&grid, &one, Vec3::ZERO, k, f32::INFINITY);
        check_knn(&grid, &one, Vec3::ZERO, k, 1.0);
    }
}

#[test]
fn within_survives_hash_collisions() {
    // One point per cell on a 16³ lattice: 4096 occupied cells in 4096 buckets, so many buckets
    // are shared, and a radius of several cells takes both cells of a shared bucket.
    let mut points = Vec::new();
    for z in 0..16 {
        for y in 0..16 {
            for x in 0..16 {
                points.push((Vec3::new(x as f32, y as f32, z as f32) + 0.5) * 0.1);
            }
        }
    }
    let grid = PointGrid::build(&points, 0.1);
    let mut shared = 0;
    for i in (0..points.len()).step_by(37) {
        let (q, r) = (points[i], 0.45);
        check_within(&grid, &points, q, r);
        // Count the queries that visit some bucket through two different cells.
        let (lo, hi) = grid.cell_range(q, r).unwrap();
        let mut seen = std::collections::HashMap::new();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    seen.entry(grid.bucket([x, y, z]))
                        .or_insert_with(Vec::new)
                        .push([x, y, z]);
                }
            }
        }
        if seen.values().any(|cells| cells.len() > 1) {
            shared += 1;
        }
    }
    assert!(shared > 10, "only {shared} queries met a shared bucket");
}

#[test]
fn within_visits_cells_then_indices() {
    let points = random_points(8, 3000, Vec3::ZERO, Vec3::ONE);
    let grid = PointGrid::build(&points, 0.08);
    let mut r = rng(9);
    for _ in 0..50 {
        let q = in_box(&mut r, Vec3::ZERO, Vec3::ONE);
        let mut got = Vec::new();
        grid.for_each_within(&points, q, 0.15, |i, _| got.push(i));
        let mut want = got.clone();
        want.sort_by_key(|&i| {
            let c = grid.cell_of(points[i as usize]);
            (c[2], c[1], c[0], i)
        });
        assert_eq!(got, want);
    }
}

#[test]
fn within_falls_back_to_a_scan_for_huge_ranges() {
    // Cells of 1e-4 over a unit box: a 0.05 query covers ~10⁹ cells, far more than buckets.
    let points = random_points(10, 1500, Vec3::ZERO, Vec3::ONE);
    let grid = PointGrid::build(&points, 1e-4);
    let mut r = rng(11);
    let mut found = 0;
    for _ in 0..50 {
        let q = in_box(&mut r, Vec3::ZERO, Vec3::ONE);
        found += check_within(&grid, &points, q, 0.05);
        found += check_within(&grid, &points, q, 2e-4);
    }
    assert!(found > 0);
    assert_eq!(
        check_within(&grid, &points, Vec3::ZERO, f32::INFINITY),
        1500
    );
}

#[test]
fn k_nearest_matches_brute_force() {
    let mut r = rng(12);
    let uniform = random_points(13, 1500, Vec3::ZERO, Vec3::ONE);
    let mut clustered = Vec::new();
    for _ in 0..6 {
        let c = in_box(&mut r, Vec3::ZERO, Vec3::splat(4.0));
        for _ in 0..200 {
            clustered.push(c + in_box(&mut r, Vec3::splat(-0.01), Vec3::splat(0.01)));
        }
    }
    let mut dups = random_points(14, 300, Vec3::ZERO, Vec3::ONE);
    dups.extend(std::iter::repeat_n(Vec3::splat(0.5), 200));
    let mut lattice = Vec::new();
    for z in 0..10 {
        for y in 0..10 {
            for x in 0..10 {
                lattice.push(Vec3::new(x as f32, y as f32, z as f32) * 0.25);
            }
        }
    }
    for (points, cell) in [
        (&uniform, 0.05),
        (&uniform, 0.3),
        (&clustered, 0.02),
        (&dups, 0.1),
        (&lattice, 0.25),
    ] {
        let grid = PointGrid::build(points, cell);
        let n = points.len();
        let lo = points.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = points.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        let mut queries: Vec<Vec3> = (0..25).map(|_| in_box(&mut r, lo, hi)).collect();
        queries.extend((0..n).step_by(n / 8).map(|i| points[i]));
        queries.push(Vec3::splat(0.5)); // on the duplicates and the lattice
        queries.push(hi + Vec3::new(3.0, 0.0, 0.0)); // outside
        queries.push(lo - Vec3::splat(0.7));
        for &q in &queries {
            for k in [1, 5, 50, n, n + 10] {
                for max_r in [f32::INFINITY, 0.05, 0.25] {
                    check_knn(&grid, points, q, k, max_r);
                }
            }
        }
    }
}

#[test]
fn k_nearest_finds_far_neighbours() {
    // Sparse points with tiny cells: the k-th neighbour lies many shells out.
    let sparse = random_points(15, 40, Vec3::ZERO, Vec3::splat(10.0));
    let grid = PointGrid::build(&sparse, 0.05);
    let mut r = rng(16);
    for _ in 0..30 {
        let q = in_box(&mut r, Vec3::splat(-2.0), Vec3::splat(12.0));
        for k in [1, 5, 39] {
            check_knn(&grid, &sparse, q, k, f32::INFINITY);
            check_knn(&grid, &sparse, q, k, 3.0);
        }
    }
    // A flat set (one cell thick) queried from above it and from far away.
    let mut flat = random_points(17, 600, Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0));
    flat.push(Vec3::new(0.5, 0.0, 0.5));
    let grid = PointGrid::build(&flat, 0.01);
    for q in [
        Vec3::new(0.5, 0.3, 0.5),
        Vec3::new(0.5, 0.001, 0.5),
        Vec3::splat(40.0),
    ] {
        for k in [1, 5, 50] {
            check_knn(&grid, &flat, q, k, f32::INFINITY);
        }
    }
    // Far from the origin, where rounding is coarse.
    let far = random_points(18, 800, Vec3::splat(1e4), Vec3::splat(1e4 + 1.0));
    let grid = PointGrid::build(&far, 0.02);
    for i in (0..800).step_by(53) {
        for k in [1, 5, 50] {
            check_knn(&grid, &far, far[i], k, f32::INFINITY);
            check_knn(&grid, &far, far[i] + Vec3::splat(0.01), k, 0.05);
        }
    }
}

#[test]
fn build_and_queries_do_not_depend_on_thread_count() {
    let mut points = random_points(19, 60_000, Vec3::splat(-1.0), Vec3::ONE);
    // Signed zeros at the box minimum: which one min() keeps depends on the split, and the
    // grid's origin must not.
    for p in &mut points {
        p.x = p.x.abs();
    }
    for i in (0..points.len()).step_by(1000) {
        points[i].x = if i == 0 { 0.0 } else { -0.0 };
    }
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let grid = PointGrid::build(&points, 0.04);
            let mut visits = Vec::new();
            let mut r = rng(20);
            let mut out = Vec::new();
            for _ in 0..200 {
                let q = in_box(&mut r, Vec3::splat(-1.0), Vec3::ONE);
                grid.for_each_within(&points, q, 0.05, |i, d2| visits.push((i, d2)));
                grid.k_nearest(&points, q, 8, f32::INFINITY, &mut out);
                visits.extend_from_slice(&out);
            }
            (grid, visits)
        })
    };
    let (g1, v1) = run(1);
    let (g4, v4) = run(4);
    assert_eq!(g1.min.x.to_bits(), 0.0f32.to_bits());
    assert_eq!(g1, g4);
    assert!(v1.len() > 1000);
    assert_eq!(v1, v4);
}

#[test]
fn within_squared_tests_against_r2_itself() {
    // r² is each query's exact squared distance to another point: that point lies on the
    // boundary, and a test against sqrt(r²)² would lose it whenever the root rounds down.
    let points = random_points(21, 2000, Vec3::ZERO, Vec3::ONE);
    let grid = PointGrid::build(&points, 0.1);
    let mut on_boundary = 0;
    for i in (0..points.len()).step_by(7) {
        let q = points[i];
        let r2 = (points[(i * 31 + 5) % points.len()] - q).length_squared();
        let mut got = Vec::new();
        grid.for_each_within_squared(&points, q, r2, |k, d2| got.push((k, d2)));
        got.sort_unstable_by_key(|e| e.0);
        let want: Vec<(u32, f32)> = (0..points.len() as u32)
            .map(|k| (k, (points[k as usize] - q).length_squared()))
            .filter(|&(_, d2)| d2 <= r2)
            .collect();
        assert_eq!(got, want, "q = {q:?}, r2 = {r2}");
        on_boundary += (r2.sqrt() * r2.sqrt() < r2) as u32;
    }
    assert!(on_boundary > 0, "no query had a root that rounds down");
}

#[test]
fn reordered_points_are_met_in_the_same_order() {
    let points = random_points(22, 3000, Vec3::ZERO, Vec3::ONE);
    let grid = PointGrid::build(&points, 0.05);
    let (mut sorted, mut payload) = (points.clone(), (0..3000u32).collect::<Vec<_>>());
    let (regrid, original) = PointGrid::build_reordered(&mut sorted, &mut payload, 0.05);
    assert_eq!(payload, original);
    assert_eq!(
        regrid.bucket_order(),
        (0..points.len() as u32).collect::<Vec<_>>()
    );
    let mut r = rng(23);
    for _ in 0..200 {
        let q = in_box(&mut r, Vec3::ZERO, Vec3::ONE);
        let (mut before, mut after) = (Vec::new(), Vec::new());
        grid.for_each_within(&points, q, 0.07, |i, d2| before.push((i, d2)));
        regrid.for_each_within(&sorted, q, 0.07, |s, d2| {
            after.push((original[s as usize], d2))
        });
        assert_eq!(before, after, "q = {q:?}");
    }
}
