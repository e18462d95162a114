//! `lt study radius-shrinkage-media`: the radius schedules of the volumetric density estimators
//! (`volume_density/schedule.rs`: rᵢ = r₁ i^((α−1)/d), variance ∝ N^(−α), bias² ∝
//! N^(−min(2, 4(1−α)/d))) measured where the answer is exact: `pp3d` (d = 3), `pb2d` (d = 2) and
//! `bb1d` (d = 1) on `scenes/studies/medium-point.toml`, a cube of grey isotropic fog lit by a
//! point light inside it, max_depth 2 (single scattering only). Every estimator is measured in
//! process with its own photon walk and streams (`photons::trace`, `PhotonBeams::trace`), its
//! own query and its own radius (`schedule::radius_scale`), on fixed queries, so the photons
//! are the only randomness (K runs: photon seeds 1..=K):
//!
//! - **pp3d at frozen points** (`frozen_points`, `PointQuery::at_scatter`), against the exact
//!   in-scattered radiance L_i(x) = ∫ f_p L dω = (1/4π) I T(x, light)/|x − light|²
//!   (`in_scattered`). Rendered, pp3d's free-flight query point added a 1/N variance of its own
//!   that hid the kernel's N^(−α). The points stay ≥ r₁ from the faces and the light.
//! - **pb2d and bb1d on frozen camera beams** (`frozen_rays`: the camera's pixel-centre lines,
//!   queried through `MediumEvents::along_flight` as the camera's first flight in the fog),
//!   against each beam's exact single scattering
//!
//!   L(beam) = ∫ T(entry, y) σs (1/4π) I T(y, light) / |y − light|² ds   (`single_scattering`).
//!
//! bias² and variance come from the runs' spread on every point or beam
//! (`radius_plane::measured_rates`: (m − L)² − s²/K and s², averaged; jackknife intervals over
//! runs; slopes over the tail N ≥ N_max/8). Their predictions at these N are exact, not K&Z's r²
//! expansion: one pass's expectation and variance at each radius rᵢ by quadrature of the
//! analytic field (ball averages for pp3d, `beam_moments` for pb2d and bb1d), so
//! bias_N = N⁻¹ Σᵢ (E_rᵢ − L) and Var_N = N⁻² Σᵢ Var_rᵢ (`exact_points_curves`,
//! `exact_beam_curves`); K&Z's model at these N and its asymptotic rates stand beside them.

use super::beam_moments::{Moments, PointInFog};
use super::metrics::alpha_text;
use super::output::{num, pct, slope_cells, StudyOutput};
use super::radius_plane::{gauss_legendre_unit, measured_rates, slope, MeasuredRates};
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_core::geometry::Ray;
use lt_core::math::Vec3;
use lt_integrators::media::pt::MediumEvents;
use lt_integrators::volume_density::photon_beams::{self, BeamKernel, PhotonBeams};
use lt_integrators::volume_density::points::PointQuery;
use lt_integrators::volume_density::schedule::radius_scale;
use lt_integrators::volume_density::schedule::{balanced_alpha, predicted_rates};
use lt_integrators::volume_density::{beams, photons};
use rayon::prelude::*;
use std::path::PathBuf;

pub const NAME: &str = "radius-shrinkage-media";

/// The scene's numbers (`scenes/studies/medium-point.toml`), for the exact reference.
pub const CUBE_HALF: f64 = 2.0;
pub const SIGMA_T: f64 = 0.5;
pub const ALBEDO: f64 = 0.8;
pub const LIGHT: [f64; 3] = [1.3, 0.0, 0.0];
pub const INTENSITY: f64 = 10.0;
/// r₁ for all three kernels: large enough that bias dominates the first passes (L changes by
/// tens of per cent over it on the light's side), small against the cube.
pub const R1: f64 = 0.5;

/// (estimator, kernel dimension d).
pub const ESTIMATORS: [(&str, u32); 3] = [("pp3d", 3), ("pb2d", 2), ("bb1d", 1)];

/// The α of each estimator: 0.3, 0.5, the balanced 4/(d + 4), 0.9; for d = 1 also 2/3, because
/// at α 0.3 the 1-D kernel's bias² falls below its runs' variance within the passes measured
/// (`unresolved`), and the issue asks for four α whose bias² slope is seen.
pub fn alphas(d: u32) -> Vec<f64> {
    let mut a = vec![0.3, 0.5, balanced_alpha(d), 0.9];
    if d == 1 {
        a.insert(2, 2.0 / 3.0);
    }
    a
}

pub fn scene(scale: &Scale) -> PathBuf {
    scale.scene_beside_focus("studies/medium-point.toml")
}

/// (runs, passes, photon-path divisor) at a scale. The committed scale (16 runs of 128 passes,
/// a quarter of `photon_paths`: 256 passes at half of them did not fit the round's time on the
/// shared machine) is the one results/radius-shrinkage-media/ holds (its cost:
/// results/points-beams.md); quick is for trying changes.
pub fn media_scale(scale: &Scale) -> (usize, u32, u64) {
    match scale.name {
        "full" | "committed" => (16, 128, 4),
        "test" => (4, 8, 100),
        _ => (8, 64, 10),
    }
}

/// Photon paths per pass of each estimator before the scale's divisor: a kernel of lower
/// dimension gathers from more of them per query (pb2d's 2-D kernel from a cylinder, bb1d's beams
/// from every flight crossing the camera beam, so fewer paths serve it).
pub fn photon_paths(estimator: &str) -> u64 {
    match estimator {
        "pp3d" => 5_000,
        "pb2d" => 20_000,
        _ => 2_000,
    }
}

/// The K runs of one estimator and α: seeds 1..=K.
pub fn config_specs(scale: &Scale, estimator: &str, alpha: f64) -> Vec<RunSpec> {
    let (runs, n, divisor) = media_scale(scale);
    let photons = (photon_paths(estimator) / divisor).max(1);
    (0..runs)
        .map(|r| {
            RunSpec::new(scene(scale), estimator, 1 + r as u64, n)
                .snapshots(Scale::doublings(n))
                .param("alpha", format!("{alpha}"))
                .param("photons_per_pass", photons)
                .param("radius", R1)
        })
        .collect()
}

/// No renders: every estimator is measured in process (`measure_frozen_points`,
/// `measure_frozen_beams`).
pub fn specs(_scale: &Scale) -> Vec<RunSpec> {
    Vec::new()
}

/// K&Z's model at the measured N rather than in the limit: pass i's bias ∝ rᵢ² ∝ i^(−2(1−α)/d)
/// and variance ∝ 1/rᵢ^d ∝ i^(1−α), the mean of n passes summed exactly (bias_n = n⁻¹ Σ bias_i,
/// Var_n = n⁻² Σ Var_i), its log-slope fitted over the same tail as the measurement (N ≥ N_max/8).
/// Returns (variance, bias²). The sums' finite-n terms (Σ i^(−β) converging for β > 1, its
/// ln n at β = 1) are what make this differ from `predicted_rates` at a few hundred passes.
pub fn predicted_at_these_n(alpha: f64, d: u32, snaps: &[u32]) -> Result<(f64, f64), String> {
    let last = *snaps.last().unwrap_or(&1);
    let tail: Vec<u32> = snaps.iter().copied().filter(|&n| 8 * n >= last).collect();
    let beta = 2.0 * (1.0 - alpha) / d as f64;
    let xs: Vec<f64> = tail.iter().map(|&n| (n as f64).ln()).collect();
    let sum = |n: u32, p: f64| (1..=n).map(|i| (i as f64).powf(p)).sum::<f64>();
    let var: Vec<f64> = tail
        .iter()
        .map(|&n| sum(n, 1.0 - alpha) / (n as f64).powi(2))
        .collect();
    let bias2: Vec<f64> = tail
        .iter()
        .map(|&n| (sum(n, -beta) / n as f64).powi(2))
        .collect();
    Ok((slope(&xs, &var)?, slope(&xs, &bias2)?))
}

/// pp3d's frozen query points: a 4³ grid over [−1.2, 1.2]³. Each is ≥ 0.8 from the cube's faces
/// and ≥ 0.57 from the light, so the largest kernel ball (r₁ = 0.5) holds neither.
pub fn frozen_points() -> Vec<[f64; 3]> {
    let c = |k: usize| -1.2 + 0.8 * k as f64;
    (0..64)
        .map(|i| [c(i % 4), c(i / 4 % 4), c(i / 16)])
        .collect()
}

/// The exact in-scattered radiance ∫ f_p(ω_o, ω) L(x, ω) dω at x (isotropic phase, single
/// scattering): (1/4π) I exp(−σt |x − light|) / |x − light|² — what pp3d's 3-D kernel estimates
/// (`points.rs`: the photons' power carries no σs).
pub fn in_scattered(x: [f64; 3]) -> f64 {
    let d2: f64 = (0..3).map(|k| (x[k] - LIGHT[k]).powi(2)).sum();
    INTENSITY * (-SIGMA_T * d2.sqrt()).exp() / (4.0 * std::f64::consts::PI * d2)
}

/// Measured slope of quantity `q` (0 bias², 1 variance) against α for each estimator, with its
/// interval, beside the predicted asymptotic curve of each kernel dimension.
fn rate_chart(out: &mut StudyOutput, ms: &[Measured], q: usize) -> Result<(), String> {
    let mut series = Vec::new();
    for (k, &(e, d)) in ESTIMATORS.iter().enumerate() {
        // Shifted by ±0.01 in α so the intervals do not overlap.
        let shift = 0.01 * (k as f64 - 1.0);
        let pts: Vec<(f64, f64, (f64, f64))> = ms
            .iter()
            .filter(|m| m.estimator == e)
            .filter_map(|m| {
                let j = m.rates.slopes[q].as_ref().ok()?;
                Some((m.alpha + shift, j.estimate, (j.interval.lo, j.interval.hi)))
            })
            .collect();
        series.push(Series {
            name: format!("measured: {e} (d {d})"),
            points: pts.iter().map(|p| (p.0, p.1)).collect(),
            y_interval: pts.iter().map(|p| p.2).collect(),
            style: Style::Measured,
        });
        series.push(Series {
            name: format!("predicted, d {d}"),
            points: (0..=70)
                .map(|i| {
                    let a = 0.25 + 0.7 * i as f64 / 70.0;
                    let (v, b) = predicted_rates(a, d);
                    (a, [b, v][q])
                })
                .collect(),
            y_interval: Vec::new(),
            style: Style::Fitted,
        });
    }
    let name = ["bias2-rates", "variance-rates"][q];
    out.chart(
        name,
        &Chart {
            title: format!(
                "{}: measured slope against α, per kernel dimension",
                QUANTITIES[q]
            ),
            x_label: "α".into(),
            y_label: format!("slope of ln {} against ln N", QUANTITIES[q]),
            log_x: false,
            log_y: false,
            series,
        },
        "Points: measured slopes with 95 % jackknife intervals (shifted ±0.01 in α); lines: the \
         asymptotic predictions of schedule.rs.",
    )
}

/// The ball average of `in_scattered` over radius r about x: what one pass of pp3d's 3-D kernel
/// expects there (`points.rs`; the light lies outside every ball, so the integrand is smooth).
/// Product Gauss rule: Gauss–Legendre in radius (weight ρ²) and in cos θ, the trapezoid rule in φ
/// (exact for the periodic integrand's low modes).
pub fn ball_average(x: [f64; 3], r: f64, nodes: &[(f64, f64)]) -> f64 {
    let n_phi = 2 * nodes.len();
    let mut sum = 0.0;
    for &(u, wu) in nodes {
        let rho = r * u;
        for &(c, wc) in nodes {
            let cos_t = 2.0 * c - 1.0;
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            for k in 0..n_phi {
                let phi = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / n_phi as f64;
                let y = [
                    x[0] + rho * sin_t * phi.cos(),
                    x[1] + rho * sin_t * phi.sin(),
                    x[2] + rho * cos_t,
                ];
                // ∫ over the ball = ∫ ρ² dρ dcosθ dφ; the mean divides by (4/3)πr³.
                sum += wu * wc * 3.0 * u * u * in_scattered(y) / n_phi as f64;
            }
        }
    }
    sum
}

/// Gauss nodes per axis of `ball_average`: against 40, its error is ≤ 1e-3 of the bias it
/// measures at every frozen point (`ball_average_resolves_the_bias`; 12 nodes left 1 %).
pub const BALL_NODES: usize = 20;

/// pp3d's exact bias² and variance at the frozen points after each snapshot N (no r²
/// expansion): bias_N(x) = N⁻¹ Σᵢ (ball average at rᵢ − L_i(x)), squared and averaged over the
/// points; Var_N = N⁻² Σᵢ Var(X | rᵢ)/M. One photon path's X = w f_p/V 1{in the ball} (w = 4πI/σt
/// its photon's power, `beam_moments`' pb2d; V = (4/3)πr³), so E[X²] = (w f_p/V) E[X].
pub fn exact_points_curves(alpha: f64, paths: u64, snaps: &[u32]) -> (Vec<f64>, Vec<f64>) {
    let nodes = gauss_legendre_unit(BALL_NODES);
    let points = frozen_points();
    let last = *snaps.last().unwrap_or(&1);
    let w = 4.0 * std::f64::consts::PI * INTENSITY / SIGMA_T;
    let phase = 1.0 / (4.0 * std::f64::consts::PI);
    let per_point: Vec<Vec<(f64, f64)>> = points
        .par_iter()
        .map(|&x| {
            let l = in_scattered(x);
            let (mut sum, mut var) = (0.0, 0.0);
            let mut out = Vec::new();
            for i in 1..=last {
                let r = R1 * radius_scale(i, alpha, 3);
                let mean = ball_average(x, r, &nodes);
                let volume = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
                sum += mean - l;
                var += (w * phase / volume * mean - mean * mean) / paths as f64;
                if snaps.contains(&i) {
                    let n = i as f64;
                    out.push(((sum / n).powi(2), var / (n * n)));
                }
            }
            out
        })
        .collect();
    let np = points.len() as f64;
    (0..snaps.len())
        .map(|k| {
            let (b, v) = per_point
                .iter()
                .fold((0.0, 0.0), |(b, v), p| (b + p[k].0, v + p[k].1));
            (b / np, v / np)
        })
        .unzip()
}

/// pp3d's kernel at the frozen points: K runs (photon seeds 1..=K) of N passes, pass i with its
/// own photons (`photons::trace`, the integrator's streams) and radius r₁ i^((α−1)/3), the mean
/// of the passes' `PointQuery::at_scatter` at every point and snapshot. Same numbers at any thread
/// count (the photons are traced in path order; each run sums its passes in order).
pub fn measure_frozen_points(ctx: &StudyContext, alpha: f64) -> Result<Measured, String> {
    let (runs, n, divisor) = media_scale(&ctx.scale);
    let paths = (photon_paths("pp3d") / divisor).max(1);
    let scene = config_specs(&ctx.scale, "pp3d", alpha)[0].load_scene()?;
    let (max_depth, rr_depth) = (2, 5);
    let points = frozen_points();
    let exact: Vec<f64> = points.iter().map(|&x| in_scattered(x)).collect();
    let snaps = Scale::doublings(n);
    let wo = Vec3::new(0.0, 0.0, 1.0);
    let started = std::time::Instant::now();
    // per_run[run][snapshot][point]
    let per_run: Vec<Vec<Vec<f64>>> = (0..runs)
        .into_par_iter()
        .map(|run| {
            let mut sum = vec![0.0f64; points.len()];
            let mut out = Vec::new();
            for pass in 0..n {
                let ph = photons::trace(&scene, max_depth, rr_depth, paths, 1 + run as u64, pass);
                let r = R1 * radius_scale(pass + 1, alpha, 3);
                let q = PointQuery::new(&scene, &ph, r as f32, max_depth);
                for (s, x) in sum.iter_mut().zip(&points) {
                    let at = Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
                    *s += q.at_scatter(at, wo, 0, 1).map_or(0.0, |c| c[0] as f64);
                }
                if snaps.contains(&(pass + 1)) {
                    out.push(sum.iter().map(|s| s / (pass + 1) as f64).collect());
                }
            }
            out
        })
        .collect();
    let wall = started.elapsed().as_secs_f64();
    let values: Vec<Vec<Vec<f64>>> = (0..snaps.len())
        .map(|k| per_run.iter().map(|r| r[k].clone()).collect())
        .collect();
    let (exact_bias2, exact_variance) = exact_points_curves(alpha, paths, &snaps);
    Ok(Measured {
        estimator: "pp3d",
        d: 3,
        alpha,
        rates: measured_rates(&values, &exact, &snaps, ctx.scale.confidence)?,
        exact_bias2,
        exact_variance,
        snaps,
        wall_seconds: wall,
    })
}

/// Single scattering along the ray o + s d (d unit) inside the cube: Gauss–Legendre over the
/// clipped interval (the integrand is smooth: the light is ≥ 0.3 from every camera ray).
pub fn single_scattering(o: [f64; 3], d: [f64; 3], nodes: &[(f64, f64)]) -> f64 {
    // Slab clip to [−h, h]³.
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k].abs() > CUBE_HALF {
                return 0.0;
            }
            continue;
        }
        let (a, b) = ((-CUBE_HALF - o[k]) / d[k], (CUBE_HALF - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    if !(t0 < t1) {
        return 0.0;
    }
    let sigma_s = SIGMA_T * ALBEDO;
    let phase = 1.0 / (4.0 * std::f64::consts::PI);
    let len = t1 - t0;
    nodes
        .iter()
        .map(|&(x, w)| {
            let s = t0 + x * len;
            let y = [o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]];
            let dl2: f64 = (0..3).map(|k| (y[k] - LIGHT[k]).powi(2)).sum();
            let tr = (-SIGMA_T * (s - t0 + dl2.sqrt())).exp();
            w * len * tr * sigma_s * phase * INTENSITY / dl2
        })
        .sum()
}

/// The frozen camera beams: the 16² pixel-centre lines (x, y) of the scene's orthographic
/// camera (half-width 1), each run from the fog's top face z = H down to its bottom face. The
/// closest passes 0.368 from the light, so from r ≈ 0.37 up the 2-D kernel's cylinder holds the
/// light and the 1-D kernel meets beams leaving it in every direction towards the line.
pub fn frozen_rays() -> Vec<[f64; 2]> {
    let c = |k: usize| -1.0 + (k as f64 + 0.5) / 8.0;
    (0..256).map(|i| [c(i % 16), c(i / 16)]).collect()
}

/// The analytic field of `scenes/studies/medium-point.toml` for `beam_moments`.
pub const FOG: PointInFog = PointInFog {
    light: LIGHT,
    half: CUBE_HALF,
    sigma_t: SIGMA_T,
    albedo: ALBEDO,
    intensity: INTENSITY,
};

/// Gauss nodes per piece of `beam_moments`' quadrature: against 48, the error is ≤ 1e-3 of the
/// bias it measures (`beam_moments_resolve_the_bias`).
pub const BEAM_NODES: usize = 24;

/// Each frozen beam's exact value ∫ T_c σs L_i ds (`single_scattering`, 128 nodes: converged to
/// 1e-9, `single_scattering_quadrature_converges`).
pub fn beam_values() -> Vec<f64> {
    let nodes = gauss_legendre_unit(128);
    frozen_rays()
        .iter()
        .map(|c| single_scattering([c[0], c[1], 5.0], [0.0, 0.0, -1.0], &nodes))
        .collect()
}

/// One pass of `estimator` ("pb2d" or "bb1d") on the frozen beams: the pass's photons (or photon
/// beams) traced by the integrator's own walk and streams, queried with its own code
/// (`MediumEvents::along_flight`) on each beam as the camera's first flight in the fog (medium 0,
/// depth 1, max_depth 2: what the camera walk asks after entering the cube).
pub fn frozen_beam_pass(
    scene: &lt_core::Scene,
    estimator: &str,
    (seed, pass, paths): (u64, u32, u64),
    r: f32,
    rays: &[[f64; 2]],
) -> Vec<f64> {
    let (max_depth, rr_depth) = (2, 5);
    if estimator == "pb2d" {
        let ph = photons::trace(scene, max_depth, rr_depth, paths, seed, pass);
        query_beams(&beams::BeamQuery::new(scene, &ph, r, max_depth), rays)
    } else {
        let pb = PhotonBeams::trace(scene, max_depth, rr_depth, paths, seed, pass);
        let kernel = (r, BeamKernel::Line1d);
        query_beams(
            &photon_beams::BeamQuery::new(scene, &pb, kernel, max_depth),
            rays,
        )
    }
}

/// `q`'s estimate on each frozen beam (channel 0: the fog is grey).
fn query_beams(q: &impl MediumEvents, rays: &[[f64; 2]]) -> Vec<f64> {
    let h = CUBE_HALF as f32;
    rays.iter()
        .map(|c| {
            let o = Vec3::new(c[0] as f32, c[1] as f32, h);
            let ray = Ray::new(o, Vec3::new(0.0, 0.0, -1.0));
            q.along_flight(&ray, 2.0 * h, 0, 1)
                .map_or(0.0, |v| v[0] as f64)
        })
        .collect()
}

/// One path's exact moments for `estimator` on the beam at `c` with radius `r`.
pub fn beam_moments(estimator: &str, c: [f64; 2], r: f64, rule: &[(f64, f64)]) -> Moments {
    if estimator == "pb2d" {
        FOG.pb2d(c, r, rule)
    } else {
        FOG.bb1d(c, r, rule)
    }
}

/// The exact bias² and variance of the N-pass mean at each snapshot, averaged over the frozen
/// beams: bias_N = N⁻¹ Σᵢ (E[X | rᵢ] − L), Var_N = N⁻² Σᵢ Var(X | rᵢ)/M (M photon paths per
/// pass). Beams at the same distance from the light share their moments (computed once).
pub fn exact_beam_curves(
    estimator: &str,
    alpha: f64,
    d: u32,
    paths: u64,
    snaps: &[u32],
) -> (Vec<f64>, Vec<f64>) {
    let rule = gauss_legendre_unit(BEAM_NODES);
    let rays = frozen_rays();
    let values = beam_values();
    let last = *snaps.last().unwrap_or(&1);
    let radii: Vec<f64> = (1..=last).map(|i| R1 * radius_scale(i, alpha, d)).collect();
    // Moments per distinct offset D (the f32 rays' exact offsets, as the queries see them).
    let mut offsets: Vec<f64> = rays.iter().map(|&c| FOG.offset(c)).collect();
    offsets.sort_by(f64::total_cmp);
    offsets.dedup();
    let per_offset: Vec<Vec<Moments>> = offsets
        .par_iter()
        .map(|&dd| {
            let c = [FOG.light[0] - dd, FOG.light[1]];
            radii
                .iter()
                .map(|&r| beam_moments(estimator, c, r, &rule))
                .collect()
        })
        .collect();
    let (mut bias2, mut var) = (vec![0.0; snaps.len()], vec![0.0; snaps.len()]);
    for (c, l) in rays.iter().zip(&values) {
        let k = offsets.partition_point(|&o| o < FOG.offset(*c));
        let (mut b, mut v, mut s) = (0.0, 0.0, 0);
        for (i, m) in per_offset[k].iter().enumerate() {
            b += m.mean - l;
            v += m.pass_variance(paths);
            let n = (i + 1) as u32;
            if snaps.get(s) == Some(&n) {
                bias2[s] += (b / n as f64).powi(2) / rays.len() as f64;
                var[s] += v / (n as f64).powi(2) / rays.len() as f64;
                s += 1;
            }
        }
    }
    (bias2, var)
}

/// pb2d's or bb1d's kernel on the frozen beams: K runs (photon seeds 1..=K) of N passes, pass i
/// with its own photons and radius r₁ i^((α−1)/d), the mean of the passes' estimates on every
/// beam at every snapshot. Same numbers at any thread count (photons traced in path order; each
/// run sums its passes in order).
pub fn measure_frozen_beams(
    ctx: &StudyContext,
    estimator: &'static str,
    d: u32,
    alpha: f64,
) -> Result<Measured, String> {
    let (runs, n, divisor) = media_scale(&ctx.scale);
    let paths = (photon_paths(estimator) / divisor).max(1);
    let scene = config_specs(&ctx.scale, estimator, alpha)[0].load_scene()?;
    let rays = frozen_rays();
    let snaps = Scale::doublings(n);
    let started = std::time::Instant::now();
    let per_run: Vec<Vec<Vec<f64>>> = (0..runs)
        .into_par_iter()
        .map(|run| {
            let mut sum = vec![0.0f64; rays.len()];
            let mut out = Vec::new();
            for pass in 0..n {
                let r = (R1 * radius_scale(pass + 1, alpha, d)) as f32;
                let v =
                    frozen_beam_pass(&scene, estimator, (1 + run as u64, pass, paths), r, &rays);
                for (s, x) in sum.iter_mut().zip(&v) {
                    *s += x;
                }
                if snaps.contains(&(pass + 1)) {
                    out.push(sum.iter().map(|s| s / (pass + 1) as f64).collect());
                }
            }
            out
        })
        .collect();
    let wall = started.elapsed().as_secs_f64();
    let values: Vec<Vec<Vec<f64>>> = (0..snaps.len())
        .map(|k| per_run.iter().map(|r| r[k].clone()).collect())
        .collect();
    let (exact_bias2, exact_variance) = exact_beam_curves(estimator, alpha, d, paths, &snaps);
    Ok(Measured {
        estimator,
        d,
        alpha,
        rates: measured_rates(&values, &beam_values(), &snaps, ctx.scale.confidence)?,
        exact_bias2,
        exact_variance,
        snaps,
        wall_seconds: wall,
    })
}

/// One estimator's and α's measurement.
pub struct Measured {
    pub estimator: &'static str,
    pub d: u32,
    pub alpha: f64,
    pub snaps: Vec<u32>,
    pub rates: MeasuredRates,
    /// Wall seconds of the in-process measurement (the exact curves not included).
    pub wall_seconds: f64,
    /// The exact bias² and variance at each snapshot (`exact_points_curves`,
    /// `exact_beam_curves`), averaged over the frozen points or beams.
    pub exact_bias2: Vec<f64>,
    pub exact_variance: Vec<f64>,
}

const QUANTITIES: [&str; 3] = ["bias²", "variance", "MSE"];

/// The slope over the tail (N ≥ N_max/8) of a curve given at every snapshot.
fn tail_slope(snaps: &[u32], ys: &[f64]) -> Result<f64, String> {
    let last = *snaps.last().unwrap_or(&1);
    let tail: Vec<usize> = (0..snaps.len()).filter(|&k| 8 * snaps[k] >= last).collect();
    let xs: Vec<f64> = tail.iter().map(|&k| (snaps[k] as f64).ln()).collect();
    let ys: Vec<f64> = tail.iter().map(|&k| ys[k]).collect();
    slope(&xs, &ys)
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let exact = beam_values();
    // The beams' reference against a finer rule.
    let finer: Vec<f64> = {
        let nodes = gauss_legendre_unit(256);
        frozen_rays()
            .iter()
            .map(|c| single_scattering([c[0], c[1], 5.0], [0.0, 0.0, -1.0], &nodes))
            .collect()
    };
    let quadrature_error = exact
        .iter()
        .zip(&finer)
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0.0, f64::max);
    let mut ms = Vec::new();
    for (e, d) in ESTIMATORS {
        for a in alphas(d) {
            ms.push(if e == "pp3d" {
                measure_frozen_points(ctx, a)?
            } else {
                measure_frozen_beams(ctx, e, d, a)?
            });
        }
    }
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Radius shrinkage in a medium: the volumetric kernels' rates against their exact finite-N \
         predictions",
        scale,
    )?;
    let (runs, passes, divisor) = media_scale(scale);
    let photons = ESTIMATORS
        .iter()
        .map(|(e, _)| format!("{} ({e})", photon_paths(e) / divisor))
        .collect::<Vec<_>>()
        .join(", ");
    let wall: f64 = ms.iter().map(|m| m.wall_seconds).sum();
    let mean_l = exact.iter().sum::<f64>() / exact.len().max(1) as f64;
    out.para(&format!(
        "pp3d (3-D kernel), pb2d (2-D) and bb1d (1-D) on `studies/medium-point` (grey isotropic \
         fog σt = {SIGMA_T}, albedo {ALBEDO}, in a cube of half-side {CUBE_HALF}, a point light \
         of intensity {INTENSITY} at (1.3, 0, 0), max_depth 2: single scattering only), each \
         with its own photon walk, streams, query code and radius schedule, in process: pp3d at \
         64 frozen points (a 4³ grid over [−1.2, 1.2]³, ≥ r₁ from the faces and the light) \
         against the exact in-scattered radiance; pb2d and bb1d on 256 frozen camera beams (the \
         camera's 16² pixel-centre lines through the cube, the closest 0.368 from the light) \
         against each beam's exact single scattering (mean {mean}; 128 nodes against 256 differ by \
         at most {qe} relative). {runs} independent runs (seeds 1…{runs}) of {passes} passes of \
         {photons} photon paths, r₁ = {R1}, rᵢ = r₁ i^((α−1)/d), at α ∈ {{0.3, 0.5, 4/(d+4), \
         0.9}}. bias² = mean over points/beams of (m − L)² − s²/K, variance = mean of s², MSE \
         their sum; {c} % delete-one jackknife intervals over runs; slopes of ln against ln N \
         over N ≥ {tail}. Predicted: exact at these N (one pass's expectation and variance at \
         each rᵢ by quadrature of the analytic field: ball averages for pp3d, `beam_moments` for \
         pb2d and bb1d; bias_N = N⁻¹ Σ (E_rᵢ − L), Var_N = N⁻² Σ Var_rᵢ), beside K&Z's model \
         at these N (pass bias ∝ rᵢ², variance ∝ rᵢ^(−d)) and its asymptotic rates \
         (schedule.rs: variance N^(−α), bias² N^(−min(2, 4(1−α)/d)), MSE the slower). Measuring: \
         {wall:.0} s wall.",
        mean = num(mean_l),
        qe = num(quadrature_error),
        c = pct(scale.confidence),
        tail = (passes / 8).max(1),
    ));
    let mut rows = Vec::new();
    for m in &ms {
        let (pv, pb) = predicted_rates(m.alpha, m.d);
        let (kz_v, kz_b) = predicted_at_these_n(m.alpha, m.d, &m.snaps)?;
        let mse: Vec<f64> = m
            .exact_bias2
            .iter()
            .zip(&m.exact_variance)
            .map(|(b, v)| b + v)
            .collect();
        let exact_rates = [
            tail_slope(&m.snaps, &m.exact_bias2)?,
            tail_slope(&m.snaps, &m.exact_variance)?,
            tail_slope(&m.snaps, &mse)?,
        ];
        let exact_last = [m.exact_bias2.last(), m.exact_variance.last(), mse.last()];
        for (q, pred, kz) in [
            (0, pb, Some(kz_b)),
            (1, pv, Some(kz_v)),
            (2, pv.max(pb), None),
        ] {
            let (meas, ci, diff, mut inside) = slope_cells(&m.rates.slopes[q], exact_rates[q]);
            // A bias² below the variance of the K runs' mean at the last N is not resolved by
            // them: the tail's slope then measures their noise (decided from the exact curves).
            let (runs, _, _) = media_scale(scale);
            let floor = m.exact_variance.last().map_or(0.0, |v| v / runs as f64);
            if q == 0 && m.exact_bias2.last().is_some_and(|&b| b < floor) {
                inside = "unresolved".into();
            }
            let (_, _, _, inside_asymptotic) = slope_cells(&m.rates.slopes[q], pred);
            let inside_kz = kz.map_or("—".into(), |k| slope_cells(&m.rates.slopes[q], k).3);
            let last = m.rates.at_n.last().map(|j| &j[q]);
            rows.push(vec![
                m.estimator.into(),
                m.d.to_string(),
                alpha_text(m.alpha),
                QUANTITIES[q].into(),
                meas,
                ci,
                num(pred),
                num(exact_rates[q]),
                diff,
                inside,
                kz.map_or("—".into(), num),
                inside_kz,
                inside_asymptotic,
                last.map_or("—".into(), |j| num(j.estimate)),
                last.map_or("—".into(), |j| num(j.std_error)),
                exact_last[q].map_or("—".into(), |&v| num(v)),
            ]);
        }
    }
    out.table(
        "rates",
        "Measured slopes against the predicted rates",
        "Slope of ln(quantity) against ln N over the tail with its jackknife interval; the \
         predicted asymptotic rate (schedule.rs; MSE: the slower of the two); the exact \
         prediction at these N (`predicted at these N`: the exact bias² and variance curves, \
         `exact_points_curves` and `exact_beam_curves`, MSE their sum, fitted over the same tail); \
         difference from it ± half-width; whether the interval holds it (`inside`); K&Z's model \
         at these N (pass biases ∝ rᵢ², variances ∝ rᵢ^(−d), summed exactly and fitted over the \
         same tail: `predicted_at_these_n`) and whether the interval holds it; whether it holds \
         the asymptotic rate; the quantity and its standard error at the last N, and its exact \
         value there. A `—` slope: the quantity is not resolved from zero in the tail; \
         `unresolved`: the exact bias² at the last N lies below the exact variance of the K \
         runs' mean (Var_N/K), so the runs cannot resolve the tail's slope (per-n.csv holds its \
         values N by N).",
        &[
            "integrator",
            "d",
            "α",
            "quantity",
            "measured",
            "CI",
            "predicted",
            "predicted at these N",
            "difference",
            "inside",
            "K&Z at these N",
            "inside K&Z at these N",
            "inside asymptotic",
            "at last N",
            "± (1 s.e.)",
            "exact at last N",
        ],
        rows,
        true,
    )?;
    for q in [1, 0] {
        rate_chart(&mut out, &ms, q)?;
    }
    let mut per_n = Vec::new();
    for m in &ms {
        for (k, &n) in m.snaps.iter().enumerate() {
            let j = &m.rates.at_n[k];
            per_n.push(vec![
                m.estimator.into(),
                alpha_text(m.alpha),
                n.to_string(),
                num(j[0].estimate),
                num(j[0].std_error),
                num(m.exact_bias2[k]),
                num(j[1].estimate),
                num(j[1].std_error),
                num(m.exact_variance[k]),
            ]);
        }
    }
    out.table(
        "per-n",
        "bias² and variance at every N",
        "Mean over the frozen points (pp3d) or beams (pb2d, bb1d), with one jackknife standard \
         error, beside the exact values (`exact_points_curves`, `exact_beam_curves`).",
        &[
            "integrator",
            "α",
            "N",
            "bias²",
            "± bias²",
            "exact bias²",
            "variance",
            "± variance",
            "exact variance",
        ],
        per_n,
        false,
    )?;
    out.finish()
}

#[cfg(test)]
mod tests;
