//! Media: Mitsuba's grid lookup convention, the exact optical depth of a trilinear grid, majorant
//! bounds, the transmittance estimators against exp(−∫σt), and the free-flight sampler against its
//! claimed density and for unbiased weights. Fields are products of linear functions, which a
//! cell-centred trilinear grid reproduces exactly inside the hull of its sample centres, so every
//! integral along a test segment is known in closed form (a cubic: Simpson's rule is exact).
//! Seeds are fixed; statistical thresholds are Šidák-corrected normal quantiles.

use lt_core::math::{gamma, Color, Mat4, Vec3};
use lt_core::medium::{
    GridMedium, GridVolume, Medium, PhaseFunction, Volume, VolumeGrid, WrapMode,
};
use lt_core::sampling::Sampler;
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
        Volume::Constant(Color::new(0.8, 0.4, 0.2)),
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
    let half = Volume::Constant(Color::splat(0.5));
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
                // Rays from outside the cube through it (the outside part has the global bound).
                let o = Vec3::new(-2.0, -0.5, -1.0)
                    + Vec3::new(5.0, 2.5, 2.0) * s.next_2d().extend(s.next_f32());
                let target = point_in_hull(&vol, &mut s);
                let d = (target - o).normalize();
                let t_max = 2.0 * o.distance(target);
                let mut covered = 0.0;
                for (t0, t1, mu) in g.majorant_segments(o, d, t_max) {
                    assert!(t0 == covered && t1 >= t0, "segments must tile [0, t_max]");
                    covered = t1;
                    for i in 0..8 {
                        let t = t0 + (t1 - t0) * (i as f32 + 0.5) / 8.0;
                        let sigma = g.sigma_t(o + d * t);
                        // One lerp's rounding may lift a convex combination by an ulp or two.
                        let slack = mu * (1.0 + 8.0 * f32::EPSILON);
                        assert!(sigma.cmple(slack).all(), "σt {sigma} > μ̄ {mu} at t {t}");
                    }
                }
                assert_eq!(covered, t_max);
            }
        }
    }
}
