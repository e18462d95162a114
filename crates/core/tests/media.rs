//! Media: Mitsuba's grid lookup convention, the exact optical depth of a trilinear grid, majorant
//! bounds, the transmittance estimators against exp(−∫σt), and the free-flight sampler against its
//! claimed density and for unbiased weights. Fields are products of linear functions, which a
//! cell-centred trilinear grid reproduces exactly inside the hull of its sample centres, so every
//! integral along a test segment is known in closed form (a cubic: Simpson's rule is exact).
//! Seeds are fixed; statistical thresholds are Šidák-corrected normal quantiles.

use lt_core::math::{gamma, Color, Mat4, Vec3};
use lt_core::medium::{
    FreeFlight, GridMedium, GridVolume, Homogeneous, Medium, PhaseFunction, TransmittanceEstimator,
    Volume, VolumeGrid, WrapMode,
};
use lt_core::sampling::Sampler;
use lt_core::testing::{sidak, MeanEstimate};
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};
use std::sync::Arc;

/// Per channel c: scale_c · (1 + 2x)(0.5 + y)(2 − 1.5z) in local coordinates: positive on the
/// unit cube, varying by ×3–8 along each axis.
fn product_field(p: [f64; 3], c: usize) -> f64 {
    let scale = [1.0, 0.4, 2.5][c];
    scale * (1.0 + 2.0 * p[0]) * (0.5 + p[1]) * (2.0 - 1.5 * p[2])
}

/// The cell-centred samples of `product_field` on a grid of `res` with `channels`.
fn product_grid(res: [usize; 3], channels: usize) -> VolumeGrid {
    let mut data = Vec::new();
    for k in 0..res[2] {
        for j in 0..res[1] {
            for i in 0..res[0] {
                let p = [
                    (i as f64 + 0.5) / res[0] as f64,
                    (j as f64 + 0.5) / res[1] as f64,
                    (k as f64 + 0.5) / res[2] as f64,
                ];
                for c in 0..channels {
                    data.push(product_field(p, c) as f32);
                }
            }
        }
    }
    VolumeGrid::new(res, channels, data, [Vec3::ZERO, Vec3::ONE]).unwrap()
}

/// The volume's placement in the tests: local [0, 1]³ → world [−1, 2] × [0, 1.5] × [−0.5, 0.5].
fn to_world() -> Mat4 {
    Mat4::from_translation(Vec3::new(-1.0, 0.0, -0.5)) * Mat4::from_scale(Vec3::new(3.0, 1.5, 1.0))
}

const SCALE: f32 = 0.6;

/// A heterogeneous medium over the product grid (σt = SCALE × field, albedo 0.8 · (1, 0.5, 0.25)).
fn product_medium(channels: usize, supervoxel: usize) -> (Medium, GridVolume) {
    let vol = GridVolume::new(
        Arc::new(product_grid([7, 5, 6], channels)),
        to_world(),
        false,
        WrapMode::Clamp,
    )
    .unwrap();
    let m = GridMedium::new(
        Volume::Grid(vol.clone()),
        SCALE,
        Volume::constant(Color::new(0.8, 0.4, 0.2)),
        PhaseFunction::Isotropic,
    )
    .unwrap()
    .with_supervoxel(supervoxel);
    (Medium::Grid(Box::new(m)), vol)
}

/// τ_c(a, b) of the analytic field (f64), with a, b world points inside the hull of centres.
fn analytic_depth(vol: &GridVolume, a: Vec3, b: Vec3, channels: usize, c: usize) -> f64 {
    let (la, lb) = (vol.local(a), vol.local(b));
    let at = |s: f64| {
        let p = [0, 1, 2].map(|k| la[k] as f64 + s * (lb[k] as f64 - la[k] as f64));
        product_field(p, if channels == 1 { 0 } else { c })
    };
    let simpson = (at(0.0) + 4.0 * at(0.5) + at(1.0)) / 6.0;
    SCALE as f64 * a.distance(b) as f64 * simpson
}

/// A world point whose local coordinates lie in the hull of sample centres of a [7, 5, 6] grid.
fn point_in_hull(vol: &GridVolume, s: &mut Sampler) -> Vec3 {
    let res = [7.0f32, 5.0, 6.0];
    let local = Vec3::from_array([0, 1, 2].map(|k| (0.5 + s.next_f32() * (res[k] - 1.0)) / res[k]));
    let w = to_world().transform_point3(local);
    // Round trip through the inverse must stay in the hull; nudge rounding back in.
    let back = vol.local(w);
    assert!((back - local).abs().max_element() < 1e-5);
    w
}

/// Segments of the tests: random chords of the hull, plus an axis-parallel and a short one.
fn segments(vol: &GridVolume, n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut s = Sampler::new(seed, 0, 0);
    let mut v: Vec<_> = (0..n)
        .map(|_| (point_in_hull(vol, &mut s), point_in_hull(vol, &mut s)))
        .collect();
    let a = point_in_hull(vol, &mut s);
    v.push((a, Vec3::new(1.5, a.y, a.z)));
    v.push((a, a + Vec3::new(0.01, -0.02, 0.005)));
    v
}

#[test]
fn lookups_follow_mitsubas_cell_centred_convention() {
    let grid = Arc::new(
        VolumeGrid::new([2, 1, 1], 1, vec![0.0, 1.0], [Vec3::splat(-1.0), Vec3::ONE]).unwrap(),
    );
    let at = |wrap, x: f32| {
        GridVolume::new(grid.clone(), Mat4::IDENTITY, false, wrap)
            .unwrap()
            .eval(Vec3::new(x, 0.3, 0.7))
            .x
    };
    // Samples at x = 1/4 and 3/4; clamped within half a cell of the faces and beyond.
    for (x, v) in [
        (0.25, 0.0),
        (0.75, 1.0),
        (0.5, 0.5),
        (0.0, 0.0),
        (-3.0, 0.0),
        (1.2, 1.0),
    ] {
        assert_eq!(at(WrapMode::Clamp, x), v, "clamp at {x}");
    }
    // At x = 1: u = 1.5, halfway from sample 1 to sample 2 ≡ 0 (repeat) or ≡ 1 (mirror).
    assert_eq!(at(WrapMode::Repeat, 1.0), 0.5);
    assert_eq!(at(WrapMode::Mirror, 1.0), 1.0);
    assert_eq!(at(WrapMode::Repeat, 1.25), 0.0);
    // to_world scales the unit cube; use_grid_bbox maps the file's box [−1, 1]³ onto it first.
    let scaled = GridVolume::new(
        grid.clone(),
        Mat4::from_scale(Vec3::splat(2.0)),
        false,
        WrapMode::Clamp,
    )
    .unwrap();
    assert_eq!(scaled.eval(Vec3::new(0.5, 0.5, 0.5)).x, 0.0);
    assert_eq!(scaled.eval(Vec3::new(1.5, 0.5, 0.5)).x, 1.0);
    let boxed = GridVolume::new(grid.clone(), Mat4::IDENTITY, true, WrapMode::Clamp).unwrap();
    assert_eq!(boxed.eval(Vec3::new(0.0, 0.0, 0.0)).x, 0.5);
    assert_eq!(boxed.eval(Vec3::new(-0.5, 0.0, 0.0)).x, 0.0);
    assert!(GridVolume::new(
        grid,
        Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)),
        false,
        WrapMode::Clamp
    )
    .is_err());
}

#[test]
fn bad_volumes_and_grid_media_are_refused() {
    let bx = [Vec3::ZERO, Vec3::ONE];
    assert!(VolumeGrid::new([2, 2, 2], 1, vec![0.0; 7], bx)
        .unwrap_err()
        .contains("need 8"));
    assert!(VolumeGrid::new([2, 2, 2], 2, vec![0.0; 16], bx)
        .unwrap_err()
        .contains("channels"));
    assert!(VolumeGrid::new([2, 2, 0], 1, vec![], bx).is_err());
    assert!(VolumeGrid::new([1, 1, 1], 1, vec![f32::NAN], bx)
        .unwrap_err()
        .contains("value 0"));
    let vol = |v: f32| {
        Volume::Grid(
            GridVolume::new(
                Arc::new(VolumeGrid::new([1, 1, 2], 1, vec![0.5, v], bx).unwrap()),
                Mat4::IDENTITY,
                false,
                WrapMode::Clamp,
            )
            .unwrap(),
        )
    };
    let iso = PhaseFunction::Isotropic;
    let half = Volume::constant(Color::splat(0.5));
    assert!(GridMedium::new(vol(-1.0), 1.0, half.clone(), iso)
        .unwrap_err()
        .contains("sigma_t"));
    assert!(GridMedium::new(vol(1.0), 1.0, vol(1.5), iso)
        .unwrap_err()
        .contains("albedo"));
    assert!(GridMedium::new(vol(1.0), -1.0, half.clone(), iso)
        .unwrap_err()
        .contains("scale"));
    assert!(GridMedium::new(
        vol(1.0),
        1.0,
        half,
        PhaseFunction::HenyeyGreenstein { g: -1.0 }
    )
    .is_err());
}

#[test]
fn grid_optical_depth_is_the_exact_integral_of_the_trilinear_field() {
    for channels in [1, 3] {
        let (m, vol) = product_medium(channels, 4);
        for (a, b) in segments(&vol, 200, 3) {
            let t = m.transmittance(a, b);
            // Planes crossed by the segment, each piece a GL pair and a sum: ≲ 8 roundings per piece
            // and 16 for the sample-space map.
            let pieces = 3.0 * (7.0 + 5.0 + 6.0);
            let bound = gamma(8 * pieces as i32 + 16) as f64;
            for c in 0..3 {
                let exact = analytic_depth(&vol, a, b, channels, c);
                let got = -(t[c] as f64).ln();
                assert!(
                    (got - exact).abs() <= bound * exact + 4.0 * f32::EPSILON as f64,
                    "{channels} ch, channel {c}, {a} → {b}: τ = {got} vs {exact}"
                );
            }
        }
    }
}

#[test]
fn majorants_bound_the_field_along_every_segment() {
    for channels in [1, 3] {
        for supervoxel in [1, 2, 4] {
            let (m, vol) = product_medium(channels, supervoxel);
            let Medium::Grid(g) = &m else { unreachable!() };
            let mut s = Sampler::new(9, supervoxel as u64, 0);
            for _ in 0..300 {
                // Rays from outside the cube through it: the segments tile the part inside it
                // (outside, σt is zero and nothing is tracked).
                let o = Vec3::new(-2.0, -0.5, -1.0)
                    + Vec3::new(5.0, 2.5, 2.0) * s.next_2d().extend(s.next_f32());
                let target = point_in_hull(&vol, &mut s);
                let d = (target - o).normalize();
                let t_max = 2.0 * o.distance(target);
                let (t_in, t_out) = g.clip(o, d, t_max).expect("the ray meets the cube");
                let mut covered = t_in;
                for (t0, t1, mu) in g.majorant_segments(o, d, t_max) {
                    assert!(
                        t0 == covered && t1 >= t0,
                        "segments must tile [t_in, t_out]"
                    );
                    covered = t1;
                    for i in 0..8 {
                        let t = t0 + (t1 - t0) * (i as f32 + 0.5) / 8.0;
                        let sigma = g.sigma_t(o + d * t);
                        // One lerp's rounding may lift a convex combination by an ulp or two.
                        let slack = mu * (1.0 + 8.0 * f32::EPSILON);
                        assert!(sigma.cmple(slack).all(), "σt {sigma} > μ̄ {mu} at t {t}");
                    }
                }
                assert_eq!(covered, t_out);
            }
        }
    }
}

/// Two-sided z threshold at the Šidák per-test level of `tests` tests at family-wise `ALPHA`.
fn z_threshold(tests: usize) -> f64 {
    let level = sidak(ALPHA, tests);
    Normal::standard().inverse_cdf(1.0 - 0.5 * level)
}

/// Family-wise false-alarm rate of each statistical test below.
const ALPHA: f64 = 0.01;

/// z-tests of estimates against references; failures listed, with the threshold for `tests`.
fn z_failures(cases: &[(String, MeanEstimate, f64)], tests: usize) -> Vec<String> {
    let z_max = z_threshold(tests);
    let mut failures = Vec::new();
    let mut worst = 0.0f64;
    for (name, est, exact) in cases {
        let z = (est.mean() - exact) / est.std_error().max(f64::MIN_POSITIVE);
        // An estimator with zero variance (a homogeneous pass) must be exact to f32 rounding.
        let ok = if est.std_error() == 0.0 {
            (est.mean() - exact).abs() <= 16.0 * f32::EPSILON as f64 * exact.abs()
        } else {
            z.abs() <= z_max
        };
        worst = worst.max(if est.std_error() == 0.0 { 0.0 } else { z.abs() });
        if !ok {
            failures.push(format!(
                "{name}: {:.6} ± {:.2e} vs {exact:.6} (z = {z:.2})",
                est.mean(),
                est.std_error()
            ));
        }
    }
    eprintln!(
        "{} z-tests, threshold |z| ≤ {z_max:.2}, largest |z| = {worst:.2}",
        cases.len()
    );
    failures
}

#[test]
fn transmittance_estimators_are_unbiased_against_the_closed_form() {
    const N: usize = 20_000;
    let mut cases = Vec::new();
    for channels in [1, 3] {
        let (m, vol) = product_medium(channels, 1);
        let Medium::Grid(g) = &m else { unreachable!() };
        for estimator in [TransmittanceEstimator::Ratio, TransmittanceEstimator::Delta] {
            for (k, (a, b)) in segments(&vol, 5, 21).into_iter().enumerate() {
                let mut s = Sampler::new(31, k as u64, channels as u64);
                let mut est = [MeanEstimate::default(); 3];
                for _ in 0..N {
                    let t = g.transmittance_estimate_with(estimator, a, b, &mut s);
                    for c in 0..3 {
                        est[c].add(t[c] as f64);
                    }
                }
                for (c, e) in est.into_iter().enumerate() {
                    let exact = (-analytic_depth(&vol, a, b, channels, c)).exp();
                    let name = format!("{estimator:?} {channels} ch segment {k} channel {c}");
                    cases.push((name, e, exact));
                }
            }
        }
    }
    let failures = z_failures(&cases, cases.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The media of the free-flight tests: chromatic homogeneous, and the grid with 1 and 3 channels.
/// A named medium with the segments it is tested on.
type MediumCase = (String, Medium, Vec<(Vec3, Vec3)>);

fn free_flight_media() -> Vec<MediumCase> {
    let homogeneous = Medium::Homogeneous(
        Homogeneous::new(
            Color::new(0.5, 1.5, 3.0),
            Color::new(0.9, 0.6, 0.3),
            1.0,
            PhaseFunction::Isotropic,
        )
        .unwrap(),
    );
    let line = |o: Vec3, t: f32| (o, o + Vec3::new(0.6, 0.0, 0.8) * t);
    let mut v = vec![(
        "homogeneous".to_string(),
        homogeneous,
        vec![line(Vec3::ZERO, 0.3), line(Vec3::ONE, 1.5)],
    )];
    for channels in [1, 3] {
        let (m, vol) = product_medium(channels, 1);
        v.push((format!("grid {channels} ch"), m, segments(&vol, 2, 41)));
    }
    v
}

/// ∫_t0^t1 f by 3-point Gauss–Legendre on `pieces` equal pieces, in f64.
fn integrate(f: impl Fn(f64) -> [f64; 3], t0: f64, t1: f64, pieces: usize) -> [f64; 3] {
    const X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let h = (t1 - t0) / pieces as f64;
    let mut sum = [0.0; 3];
    for i in 0..pieces {
        let mid = t0 + (i as f64 + 0.5) * h;
        for (x, w) in X.iter().zip(W) {
            let v = f(mid + 0.5 * h * x);
            for c in 0..3 {
                sum[c] += 0.5 * h * w * v[c];
            }
        }
    }
    sum
}

fn c3(c: Color) -> [f64; 3] {
    [c.x as f64, c.y as f64, c.z as f64]
}

/// Pearson's χ² over cells (observed, expected), pooling cells expecting < 5; returns (χ², dof).
fn chi2(mut cells: Vec<(f64, f64)>) -> (f64, usize) {
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut chi2, mut n, mut po, mut pe) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in cells {
        po += o;
        pe += e;
        if pe >= 5.0 {
            chi2 += (po - pe) * (po - pe) / pe;
            n += 1;
            (po, pe) = (0.0, 0.0);
        }
    }
    if pe > 0.0 {
        chi2 += (po - pe) * (po - pe) / pe;
        n += 1;
    }
    (chi2, n.saturating_sub(1))
}

#[test]
fn free_flight_distances_and_pass_mass_follow_the_claimed_density_chi2() {
    const N: usize = 200_000;
    const BINS: usize = 40;
    let mut outcomes = Vec::new();
    for (name, m, segs) in free_flight_media() {
        for (k, (a, b)) in segs.into_iter().enumerate() {
            let t_max = a.distance(b);
            let d = (b - a) / t_max;
            let mut s = Sampler::new(51, k as u64, 0);
            let mut observed = vec![0.0f64; BINS + 1];
            for _ in 0..N {
                match m.sample_free_flight(a, d, t_max, &mut s) {
                    FreeFlight::Scattered { t, .. } => {
                        observed[((t / t_max * BINS as f32) as usize).min(BINS - 1)] += 1.0;
                    }
                    FreeFlight::Passed { .. } => observed[BINS] += 1.0,
                }
            }
            let density = |t: f64| {
                let p = m.free_flight_density(a, a + d * t as f32, true) as f64;
                [p; 3]
            };
            let h = t_max as f64 / BINS as f64;
            let mut cells: Vec<(f64, f64)> = (0..BINS)
                .map(|i| {
                    let e = integrate(density, i as f64 * h, (i + 1) as f64 * h, 16)[0];
                    (observed[i], N as f64 * e)
                })
                .collect();
            let pass = m.free_flight_density(a, b, false) as f64;
            cells.push((observed[BINS], N as f64 * pass));
            let total: f64 = cells.iter().map(|c| c.1).sum::<f64>() / N as f64;
            let (chi2, dof) = chi2(cells);
            let p = ChiSquared::new(dof as f64).unwrap().sf(chi2);
            let label = format!("{name} segment {k} (Σ expected = {total:.6})");
            eprintln!("{label:<48} χ² = {chi2:.1}, dof {dof}, p = {p:.4}");
            outcomes.push((label, p));
        }
    }
    let level = sidak(ALPHA, outcomes.len());
    let failures: Vec<_> = outcomes.iter().filter(|o| !(o.1 >= level)).collect();
    assert!(failures.is_empty(), "level {level:.2e}: {failures:?}");
}

#[test]
fn free_flight_weights_are_unbiased() {
    const N: usize = 100_000;
    let mut cases = Vec::new();
    for (name, m, segs) in free_flight_media() {
        for (k, (a, b)) in segs.into_iter().enumerate() {
            let t_max = a.distance(b);
            let d = (b - a) / t_max;
            let mut s = Sampler::new(61, k as u64, 0);
            let (mut scattered, mut passed) =
                ([MeanEstimate::default(); 3], [MeanEstimate::default(); 3]);
            for _ in 0..N {
                let (ws, wp) = match m.sample_free_flight(a, d, t_max, &mut s) {
                    FreeFlight::Scattered { weight, .. } => (weight, Color::ZERO),
                    FreeFlight::Passed { weight } => (Color::ZERO, weight),
                };
                for c in 0..3 {
                    scattered[c].add(ws[c] as f64);
                    passed[c].add(wp[c] as f64);
                }
            }
            // E[w·1_scattered] = ∫ σs T dt, E[w·1_passed] = T(t_max), per channel.
            let x = |t: f64| a + d * t as f32;
            let sigma_s_tr = |t: f64| {
                let p = x(t);
                c3(m.sigma_s(p) * m.transmittance(a, p))
            };
            let ref_s = integrate(sigma_s_tr, 0.0, t_max as f64, 200);
            let ref_p = c3(m.transmittance(a, b));
            for c in 0..3 {
                cases.push((
                    format!("{name} segment {k} scattered, channel {c}"),
                    scattered[c],
                    ref_s[c],
                ));
                cases.push((
                    format!("{name} segment {k} passed, channel {c}"),
                    passed[c],
                    ref_p[c],
                ));
            }
        }
    }
    let failures = z_failures(&cases, cases.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn world_bounds_are_the_placed_unit_cube() {
    let (_, vol) = product_medium(1, 1);
    let [lo, hi] = vol.world_bounds();
    let (want_lo, want_hi) = (Vec3::new(-1.0, 0.0, -0.5), Vec3::new(2.0, 1.5, 0.5));
    // Through an inverse and back: a few ulps of the extent.
    let tol = 8.0 * f32::EPSILON * 3.0;
    assert!(
        (lo - want_lo).abs().max_element() <= tol && (hi - want_hi).abs().max_element() <= tol,
        "{lo} {hi}"
    );
}

#[test]
fn an_unbounded_walk_through_a_grid_ends() {
    // σt > 0 only at the centre sample: beyond the cube the clamped field is 0 under a positive
    // bound, where tracking without an end would draw tentative collisions forever.
    let mut data = vec![0.0; 27];
    data[13] = 2.0;
    let grid = VolumeGrid::new([3, 3, 3], 1, data, [Vec3::ZERO, Vec3::ONE]).unwrap();
    let vol = GridVolume::new(Arc::new(grid), Mat4::IDENTITY, false, WrapMode::Clamp).unwrap();
    let g = GridMedium::new(
        Volume::Grid(vol),
        1.0,
        Volume::constant(Color::ONE),
        PhaseFunction::Isotropic,
    )
    .unwrap();
    let m = Medium::Grid(Box::new(g));
    let mut s = Sampler::new(71, 0, 0);
    for _ in 0..1000 {
        let d = (s.next_2d().extend(s.next_f32()) - 0.5).normalize();
        let _ = m.sample_free_flight(Vec3::splat(0.5), d, f32::INFINITY, &mut s);
    }
}

#[test]
fn homogeneous_transmittance_over_an_infinite_distance_is_a_number() {
    let h = Homogeneous::new(
        Color::new(0.0, 1.0, 2.0),
        Color::ONE,
        1.0,
        PhaseFunction::Isotropic,
    )
    .unwrap();
    assert_eq!(h.transmittance(f32::INFINITY), Color::new(1.0, 0.0, 0.0));
    assert_eq!(
        h.transmittance(1.0),
        Color::new(1.0, (-1.0f32).exp(), (-2.0f32).exp())
    );
}

/// Mitsuba's `heterogeneous` medium exists only inside its σt volume's box (`intersect_aabb` on
/// the volume's bbox, the placed unit cube; a plain value is a `constvolume` on [0, 1]³): the
/// clamped field does not extend beyond it. σt = 2 on the unit cube moved by −½ (a grid and a
/// constant): a chord of length 6 through it crosses 1 unit of medium, T = e⁻², and nothing
/// scatters outside the box. Before, the grid's clamped field and the constant filled all
/// space (T = e⁻¹², the suite's hetero_sigmat_albedo: max |z| 78).
#[test]
fn a_heterogeneous_medium_lives_in_its_sigma_t_box() {
    let to_world = Mat4::from_translation(Vec3::splat(-0.5));
    let grid = VolumeGrid::new([2, 2, 2], 1, vec![2.0; 8], [Vec3::ZERO, Vec3::ONE]).unwrap();
    let volumes = [
        Volume::Grid(GridVolume::new(Arc::new(grid), to_world, false, WrapMode::Clamp).unwrap()),
        Volume::placed_constant(Color::splat(2.0), to_world).unwrap(),
    ];
    let (a, b) = (Vec3::new(-3.0, 0.1, 0.2), Vec3::new(3.0, 0.1, 0.2));
    let (t_max, d) = (a.distance(b), (b - a).normalize());
    let want = (-2.0f64).exp();
    for sigma_t in volumes {
        let what = format!("{sigma_t:?}").chars().take(8).collect::<String>();
        let g = GridMedium::new(
            sigma_t,
            1.0,
            Volume::constant(Color::ONE),
            PhaseFunction::Isotropic,
        )
        .unwrap();
        let m = Medium::Grid(Box::new(g));
        assert_eq!(m.sigma_t(Vec3::new(0.7, 0.1, 0.2)), Color::ZERO, "{what}");
        let t = m.transmittance(a, b).x as f64;
        assert!(
            (t - want).abs() <= 1e-5 * want,
            "{what}: T = {t}, want e⁻² = {want}"
        );
        const N: usize = 4000;
        let (mut est, mut passed) = (MeanEstimate::default(), MeanEstimate::default());
        let mut s = Sampler::new(81, 0, 0);
        for _ in 0..N {
            est.add(m.transmittance_estimate(a, b, &mut s).x as f64);
            match m.sample_free_flight(a, d, t_max, &mut s) {
                FreeFlight::Scattered { t, .. } => {
                    assert!(
                        (2.5 - 1e-4..=3.5 + 1e-4).contains(&t),
                        "{what}: scattered at {t}"
                    );
                    passed.add(0.0);
                }
                FreeFlight::Passed { .. } => passed.add(1.0),
            }
        }
        let failures = z_failures(
            &[
                (format!("{what}: T estimate"), est, want),
                (format!("{what}: pass fraction"), passed, want),
            ],
            4,
        );
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }
}

/// A shape keeps its (interior, exterior) pair's index in 16 bits: one pair more than that is
/// one clear error from `try_build` (before: a panic in `build`), and the limit itself builds.
#[test]
fn too_many_medium_pairs_is_an_error_not_a_panic() {
    use lt_core::bsdf::{Material, Null};
    use lt_core::camera::{Camera, FovAxis};
    use lt_core::scene::{
        MediumInterface, RenderSettings, SceneBuilder, ShapeGeometry, MAX_MEDIUM_INTERFACES,
    };
    let scene = |pairs: usize| {
        let camera = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 2, 2).unwrap();
        let mut b = SceneBuilder::new(camera, RenderSettings::default());
        let fog = Homogeneous::new(Color::ONE, Color::ONE, 1.0, PhaseFunction::Isotropic).unwrap();
        for _ in 0..256 {
            b.add_medium(Medium::Homogeneous(fog));
        }
        let null = b.add_material(Material::Null(Null));
        for k in 0..pairs {
            let center = Vec3::new((k % 256) as f32, (k / 256) as f32, -10.0);
            b.add_shape(
                ShapeGeometry::Sphere {
                    center,
                    radius: 0.1,
                },
                null,
                None,
                false,
            );
            b.set_last_shape_media(MediumInterface {
                interior: Some((k % 256) as u32),
                exterior: Some((k / 256) as u32),
            });
        }
        b.try_build()
    };
    // The builder adds each medium's (m, m) (the interface of a vertex on a shape naming no
    // media inside m): of the 256 such pairs the shapes below name all but (255, 255), so the
    // last count that fits is one shape fewer than the table's room.
    let limit = MAX_MEDIUM_INTERFACES - 2;
    assert!(scene(limit).is_ok());
    let Err(e) = scene(limit + 1) else {
        panic!("{} pairs built", limit + 1);
    };
    assert_eq!(
        e,
        "the shapes name 65536 distinct (interior, exterior) media pairs, each medium's (m, m) \
         included; at most 65535 are supported"
    );
}

/// An area light on a shape that names no media emits, from each of its points, into the medium
/// around that point (`Scene::light_medium_towards`): a camera walk reaching it keeps the medium
/// it arrived in (`medium_after`), so a light subpath must start there too — in the fog inside a
/// null sphere of fog, in vacuum outside it, and on a lamp straddling the sphere's boundary, on
/// each side its own (one medium per light, found once at build, failed the last case).
#[test]
fn an_unnamed_emitter_emits_into_the_medium_around_each_point() {
    use lt_core::bsdf::{Diffuse, Material, Null};
    use lt_core::camera::{Camera, FovAxis};
    use lt_core::scene::{MediumInterface, RenderSettings, SceneBuilder, ShapeGeometry};
    use lt_core::texture::Texture;
    // A lamp of radius 0.5 at `lamp` beside a fog sphere of radius 2 at the origin.
    let scene = |lamp: Vec3| {
        let camera =
            Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 2, 2).unwrap();
        let mut b = SceneBuilder::new(camera, RenderSettings::default());
        let fog =
            Homogeneous::new(Color::ONE, Color::splat(0.5), 1.0, PhaseFunction::Isotropic).unwrap();
        let fog = b.add_medium(Medium::Homogeneous(fog));
        let null = b.add_material(Material::Null(Null));
        let white = b.add_material(Material::Diffuse(Diffuse {
            albedo: Color::splat(0.5),
        }));
        b.add_shape(
            ShapeGeometry::Sphere {
                center: Vec3::ZERO,
                radius: 2.0,
            },
            null,
            None,
            false,
        );
        b.set_last_shape_media(MediumInterface {
            interior: Some(fog),
            exterior: None,
        });
        b.add_emitting_shape(
            ShapeGeometry::Sphere {
                center: lamp,
                radius: 0.5,
            },
            white,
            Some(Texture::Constant(Color::ONE)),
            false,
        );
        b.try_build().unwrap()
    };
    // Emitted from the lamp's point `p` along its outward normal.
    let emits_into = |scene: &lt_core::Scene, p: Vec3, n: Vec3| {
        let at = lt_core::scene::ConnectionEnd {
            p,
            p_err: Vec3::splat(1e-6),
            ng: n,
            infinite: false,
        };
        scene.light_medium_towards(0, at, n)
    };
    let inside = scene(Vec3::ZERO);
    assert_eq!(
        emits_into(&inside, Vec3::X * 0.5, Vec3::X),
        Some(0),
        "a lamp inside the fog"
    );
    let outside = scene(Vec3::X * 4.0);
    assert_eq!(
        emits_into(&outside, Vec3::X * 4.5, Vec3::X),
        None,
        "a lamp outside the fog"
    );
    // Straddling the fog's boundary at x = 2: each point emits into its own side.
    let straddling = scene(Vec3::X * 2.0);
    assert_eq!(
        emits_into(&straddling, Vec3::X * 1.5, -Vec3::X),
        Some(0),
        "its part in the fog"
    );
    assert_eq!(
        emits_into(&straddling, Vec3::X * 2.5, Vec3::X),
        None,
        "its part outside"
    );
}
