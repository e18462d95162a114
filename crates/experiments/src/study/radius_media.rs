//! `lt study radius-shrinkage-media`: the radius schedules of the volumetric density estimators
//! (`volume_density/schedule.rs`: rᵢ = r₁ i^((α−1)/d), variance ∝ N^(−α), bias² ∝
//! N^(−4(1−α)/d)) measured where the answer is exact: `pp3d` (d = 3), `pb2d` (d = 2) and `bb1d`
//! (d = 1) on `scenes/studies/medium-point.toml`, a cube of grey isotropic fog lit by a point
//! light inside it, max_depth 2 (single scattering only), seen by an orthographic camera. Every
//! pixel's value is exact by quadrature (`exact_pixels`): the box-filtered pixel's average, over
//! its rays, of
//!
//!   L(ray) = ∫ T(entry, y) σs (1/4π) I T(y, light) / |y − light|² ds
//!
//! over the ray's part inside the cube (T = exp(−σt d): homogeneous). No pixel sees the light
//! closer than 0.3, so L is smooth (and the quadrature converges fast) in every pixel.
//!
//! The K runs differ in their seeds (photons and camera samples); bias² and variance come from
//! the runs' spread at every pixel (`radius_plane::measured_rates`, the plane study's machinery:
//! per pixel (m − L)² − s²/K and s², averaged over pixels; jackknife intervals over runs; slopes
//! over the tail N ≥ N_max/8). The scene's box filter is 1/500 pixel wide, so each camera sample
//! is the pixel's centre ray to 1e-3 pixel (the plane study froze its visible points for the
//! same reason): the camera adds no variance of its own (its σ²_pixel/N is stated beside the
//! table).
//!
//! **pp3d at frozen points.** Rendered, pp3d samples its query point by free flight on the pixel's
//! ray each pass: a 1/N variance of its own that hid the kernel's N^(−α) (the first study read
//! ≈ −0.6 … −0.9 at α = 0.3 … 4/7). So pp3d is measured as the plane study measures ppm: its own
//! query (`PointQuery::at_scatter`, the photons of `photons::trace`, the radius of `schedule`) at
//! fixed points x inside the fog, against the exact in-scattered radiance
//!
//!   L_i(x) = ∫ f_p L dω = (1/4π) I T(x, light) / |x − light|²   (single scattering),
//!
//! (`in_scattered`) — K runs of independent photon streams, nothing else random. The points
//! (`frozen_points`) stay ≥ r₁ from the cube's faces and from the light, so no kernel ball ever
//! straddles the medium's boundary or holds the light's 1/d² singularity.

use super::metrics::alpha_text;
use super::output::{num, pct, slope_cells, StudyOutput};
use super::radius_plane::{gauss_legendre_unit, measured_rates, slope, MeasuredRates};
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_core::math::Vec3;
use lt_core::Vec2;
use lt_estimators::Image;
use lt_integrators::media::pt::MediumEvents;
use lt_integrators::volume_density::photons;
use lt_integrators::volume_density::points::PointQuery;
use lt_integrators::volume_density::schedule::radius_scale;
use lt_integrators::volume_density::schedule::{balanced_alpha, predicted_rates};
use rayon::prelude::*;
use std::path::PathBuf;

pub const NAME: &str = "radius-shrinkage-media";

/// The scene's numbers (`scenes/studies/medium-point.toml`), for the exact reference.
pub const CUBE_HALF: f64 = 2.0;
pub const SIGMA_T: f64 = 0.5;
pub const ALBEDO: f64 = 0.8;
pub const LIGHT: [f64; 3] = [1.3, 0.0, 0.0];
pub const INTENSITY: f64 = 10.0;
/// The box filter's radius in pixels: the camera samples (nearly) the pixel's centre ray.
pub const FILTER_RADIUS: f64 = 0.001;
/// r₁ for all three kernels: large enough that bias dominates the first passes (L changes by
/// tens of per cent over it on the light's side), small against the cube.
pub const R1: f64 = 0.5;

/// (estimator, kernel dimension d).
pub const ESTIMATORS: [(&str, u32); 3] = [("pp3d", 3), ("pb2d", 2), ("bb1d", 1)];

/// The α of each estimator: 0.3, 0.5, the balanced 4/(d + 4), 0.9.
pub fn alphas(d: u32) -> [f64; 4] {
    [0.3, 0.5, balanced_alpha(d), 0.9]
}

pub fn scene(scale: &Scale) -> PathBuf {
    scale.scene_beside_focus("studies/medium-point.toml")
}

/// (runs, passes, photon-path divisor) at a scale. The committed scale (16 runs of 256 passes,
/// half of `photon_paths`) is the one results/radius-shrinkage-media/ holds: ≈ 15 CPU-min on a
/// shared 2-core machine (pb2d at α = 0.9 keeps r ≈ r₁, so each camera beam meets most of its
/// photons); quick (≈ 11 s) is for trying changes.
pub fn media_scale(scale: &Scale) -> (usize, u32, u64) {
    match scale.name {
        "full" | "committed" => (16, 256, 2),
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

/// The renders: pb2d's and bb1d's (pp3d is measured in process at frozen points).
pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    ESTIMATORS
        .iter()
        .filter(|(e, _)| *e != "pp3d")
        .flat_map(|&(e, d)| {
            alphas(d)
                .into_iter()
                .flat_map(move |a| config_specs(scale, e, a))
        })
        .collect()
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

/// pp3d's exact bias² at the frozen points after each snapshot N (no r² expansion): bias_N(x) =
/// N⁻¹ Σᵢ (ball average at rᵢ − L_i(x)), squared and averaged over the points.
pub fn exact_points_bias2(alpha: f64, snaps: &[u32]) -> Vec<f64> {
    let nodes = gauss_legendre_unit(BALL_NODES);
    let points = frozen_points();
    let last = *snaps.last().unwrap_or(&1);
    let per_point: Vec<Vec<f64>> = points
        .par_iter()
        .map(|&x| {
            let l = in_scattered(x);
            let mut sum = 0.0;
            let mut out = Vec::new();
            for i in 1..=last {
                sum += ball_average(x, R1 * radius_scale(i, alpha, 3), &nodes) - l;
                if snaps.contains(&i) {
                    out.push(sum / i as f64);
                }
            }
            out
        })
        .collect();
    (0..snaps.len())
        .map(|k| per_point.iter().map(|b| b[k] * b[k]).sum::<f64>() / points.len() as f64)
        .collect()
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
    let values: Vec<Vec<Vec<f64>>> = (0..snaps.len())
        .map(|k| per_run.iter().map(|r| r[k].clone()).collect())
        .collect();
    Ok(Measured {
        estimator: "pp3d",
        d: 3,
        alpha,
        rates: measured_rates(&values, &exact, &snaps, ctx.scale.confidence)?,
        exact_bias2: exact_points_bias2(alpha, &snaps),
        snaps,
        cpu_seconds: 0.0,
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

/// Every pixel's exact value and its variance over the filter's box (the camera sample's own 1/N
/// term, ~0 with a box of 1/500 pixel): Gauss–Legendre `per_axis`² points over the box, the rays from the
/// scene's own camera (`Camera::generate_ray`), `along` nodes on each ray.
pub fn exact_pixels(
    spec: &RunSpec,
    per_axis: usize,
    along: usize,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let scene = spec.load_scene()?;
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let q = gauss_legendre_unit(per_axis);
    let nodes = gauss_legendre_unit(along);
    let mut mean = Vec::with_capacity(w * h);
    let mut var = Vec::with_capacity(w * h);
    for j in 0..w * h {
        let (px, py) = ((j % w) as f64, (j / w) as f64);
        let (mut m1, mut m2) = (0.0, 0.0);
        for &(u, wu) in &q {
            for &(v, wv) in &q {
                let (x, y) = (
                    px + 0.5 + (2.0 * u - 1.0) * FILTER_RADIUS,
                    py + 0.5 + (2.0 * v - 1.0) * FILTER_RADIUS,
                );
                let ray = cam.generate_ray(Vec2::new(x as f32, y as f32));
                let l = single_scattering(
                    [ray.o.x as f64, ray.o.y as f64, ray.o.z as f64],
                    [ray.d.x as f64, ray.d.y as f64, ray.d.z as f64],
                    &nodes,
                );
                m1 += wu * wv * l;
                m2 += wu * wv * l * l;
            }
        }
        mean.push(m1);
        var.push(m2 - m1 * m1);
    }
    Ok((mean, var))
}

/// One estimator's and α's measurement.
pub struct Measured {
    pub estimator: &'static str,
    pub d: u32,
    pub alpha: f64,
    pub snaps: Vec<u32>,
    pub rates: MeasuredRates,
    pub cpu_seconds: f64,
    /// pp3d at frozen points: the exact bias² at each snapshot (`exact_points_bias2`); empty
    /// for the rendered estimators.
    pub exact_bias2: Vec<f64>,
}

pub fn measure(
    ctx: &StudyContext,
    estimator: &'static str,
    d: u32,
    alpha: f64,
    exact: &[f64],
) -> Result<Measured, String> {
    let specs = config_specs(&ctx.scale, estimator, alpha);
    let entries = ctx.run_all(&specs)?;
    let snaps = specs[0].snapshots.clone();
    // values[snapshot][run][pixel]: channel 0 (a grey medium: every channel is the same).
    let values: Vec<Vec<Vec<f64>>> = snaps
        .iter()
        .map(|&n| {
            entries
                .iter()
                .map(|e| {
                    let img: Image = e.snapshot(n)?;
                    Ok(img.data.iter().map(|p| p[0]).collect())
                })
                .collect::<Result<_, String>>()
        })
        .collect::<Result<_, String>>()?;
    Ok(Measured {
        estimator,
        d,
        alpha,
        rates: measured_rates(&values, exact, &snaps, ctx.scale.confidence)?,
        snaps,
        cpu_seconds: entries
            .iter()
            .filter_map(|e| e.record.cpu_seconds.last().copied())
            .sum(),
        exact_bias2: Vec::new(),
    })
}

const QUANTITIES: [&str; 3] = ["bias²", "variance", "MSE"];

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let first = &config_specs(scale, "pb2d", 0.5)[0];
    let (exact, pixel_var) = exact_pixels(first, 8, 128)?;
    // The quadrature's own error: against a finer rule on both axes.
    let (finer, _) = exact_pixels(first, 12, 256)?;
    let quadrature_error = exact
        .iter()
        .zip(&finer)
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0.0, f64::max);
    let mut ms = Vec::new();
    let started = std::time::Instant::now();
    for a in alphas(3) {
        ms.push(measure_frozen_points(ctx, a)?);
    }
    let points_wall = started.elapsed().as_secs_f64();
    for (e, d) in ESTIMATORS.into_iter().filter(|(e, _)| *e != "pp3d") {
        for a in alphas(d) {
            ms.push(measure(ctx, e, d, a, &exact)?);
        }
    }
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Radius shrinkage in a medium: the volumetric kernels' rates measured at exact pixels",
        scale,
    )?;
    let (runs, passes, divisor) = media_scale(scale);
    let photons = ESTIMATORS
        .iter()
        .map(|(e, _)| format!("{} ({e})", photon_paths(e) / divisor))
        .collect::<Vec<_>>()
        .join(", ");
    let cpu: f64 = ms.iter().map(|m| m.cpu_seconds).sum();
    let np = exact.len().max(1) as f64;
    let sigma2 = pixel_var.iter().sum::<f64>() / np;
    let mean_l = exact.iter().sum::<f64>() / np;
    out.para(&format!(
        "pp3d (3-D kernel), pb2d (2-D) and bb1d (1-D) on `studies/medium-point` (grey isotropic \
         fog σt = {SIGMA_T}, albedo {ALBEDO}, in a cube of half-side {CUBE_HALF}, a point light \
         of intensity {INTENSITY} at (1.3, 0, 0), max_depth 2: single scattering only, exact by \
         quadrature in every pixel, mean {mean}; 8² × 128 nodes against 12² × 256 differ by at most \
         {qe} relative), {runs} independent runs (seeds 1…{runs}) of \
         {passes} passes of {photons} photon paths, r₁ = {R1}, rᵢ = r₁ i^((α−1)/d), at α ∈ \
         {{0.3, 0.5, 4/(d+4), 0.9}}. bias² = mean over pixels of (m − L)² − s²/K, variance = \
         mean of s², MSE their sum; {c} % delete-one jackknife intervals over runs; slopes of ln \
         against ln N over N ≥ {tail}. Predicted (schedule.rs): variance N^(−α), bias² \
         N^(−min(2, 4(1−α)/d)) (the mean of the passes' biases falls no faster than 1/n: the cap \
         binds for d = 1 at α ≤ 1/2). pb2d and bb1d are rendered; the camera samples the pixel's \
         centre ray (a box filter of 1/500 pixel: its own variance σ²_pixel/N = {s2}/N). pp3d is \
         measured at 64 frozen points (a 4³ grid over [−1.2, 1.2]³, ≥ r₁ from the faces and the \
         light) with its own query and photons against the exact in-scattered radiance, so its \
         free-flight query point adds no 1/N of its own; its 'pixels' are those points. Render \
         CPU (pb2d, bb1d): {cpu:.0} s; pp3d in process: {points_wall:.0} s wall.",
        mean = num(mean_l),
        qe = num(quadrature_error),
        c = pct(scale.confidence),
        tail = (passes / 8).max(1),
        s2 = num(sigma2),
    ));
    let mut rows = Vec::new();
    for m in &ms {
        let (pv, pb) = predicted_rates(m.alpha, m.d);
        let (fv, mut fb) = predicted_at_these_n(m.alpha, m.d, &m.snaps)?;
        if m.estimator == "pp3d" {
            // At the frozen points the bias is exact (ball averages): its slope over the tail.
            let last = *m.snaps.last().unwrap_or(&1);
            let tail: Vec<usize> = (0..m.snaps.len())
                .filter(|&k| 8 * m.snaps[k] >= last)
                .collect();
            let xs: Vec<f64> = tail.iter().map(|&k| (m.snaps[k] as f64).ln()).collect();
            let ys: Vec<f64> = tail.iter().map(|&k| m.exact_bias2[k]).collect();
            fb = slope(&xs, &ys)?;
        }
        let pm = pv.max(pb);
        for (q, pred, at_n) in [(0, pb, Some(fb)), (1, pv, Some(fv)), (2, pm, None)] {
            let (meas, ci, diff, inside) = slope_cells(&m.rates.slopes[q], at_n.unwrap_or(pred));
            let (_, _, _, inside_asymptotic) = slope_cells(&m.rates.slopes[q], pred);
            let last = m.rates.at_n.last().map(|j| &j[q]);
            rows.push(vec![
                m.estimator.into(),
                m.d.to_string(),
                alpha_text(m.alpha),
                QUANTITIES[q].into(),
                meas,
                ci,
                num(pred),
                at_n.map_or("—".into(), num),
                diff,
                inside,
                inside_asymptotic,
                last.map_or("—".into(), |j| num(j.estimate)),
                last.map_or("—".into(), |j| num(j.std_error)),
            ]);
        }
    }
    out.table(
        "rates",
        "Measured slopes against the predicted rates",
        "Slope of ln(quantity) against ln N over the tail with its jackknife interval; the \
         predicted asymptotic rate (schedule.rs; MSE: the slower of the two); K&Z's model at \
         these N (pass biases ∝ rᵢ², variances ∝ rᵢ^(−d), summed exactly and fitted over the \
         same tail: `predicted_at_these_n`); difference from it ± half-width; whether the \
         interval holds it (`inside`) and the asymptotic rate (`inside asymptotic`); the quantity \
         and its standard error at the last N. pp3d's bias² at these N is exact (ball averages \
         of the exact L_i at its frozen points, `exact_points_bias2`), not K&Z's r² model. A `—` slope: the quantity is not resolved from \
         zero in the tail (bias² below the runs' noise).",
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
            "inside asymptotic",
            "at last N",
            "± (1 s.e.)",
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
                num(j[1].estimate),
                num(j[1].std_error),
                m.exact_bias2.get(k).map_or("—".into(), |&b| num(b)),
            ]);
        }
    }
    out.table(
        "per-n",
        "bias² and variance at every N",
        "Mean over pixels (pp3d: over its frozen points), with one jackknife standard error; pp3d's exact bias² from ball averages (`exact_points_bias2`).",
        &[
            "integrator",
            "α",
            "N",
            "bias²",
            "± bias²",
            "variance",
            "± variance",
            "exact bias²",
        ],
        per_n,
        false,
    )?;
    out.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact pp3d bias is resolved: `ball_average` at BALL_NODES against 40 nodes differs by
    /// ≤ 1e-3 of the bias (ball average − L_i) at every frozen point and radius the study uses,
    /// and a tiny ball returns L_i itself.
    #[test]
    fn ball_average_resolves_the_bias() {
        let (a, b) = (gauss_legendre_unit(BALL_NODES), gauss_legendre_unit(40));
        for x in frozen_points() {
            let l = in_scattered(x);
            for r in [R1, 0.2, 0.05] {
                let (ra, rb) = (ball_average(x, r, &a), ball_average(x, r, &b));
                let bias = rb - l;
                assert!(
                    (ra - rb).abs() <= 1e-3 * bias.abs(),
                    "{x:?} r {r}: {ra} vs {rb}, bias {bias}"
                );
            }
            let tiny = ball_average(x, 1e-4, &a);
            assert!(((tiny - l) / l).abs() < 1e-6, "{x:?}: {tiny} vs {l}");
        }
    }

    #[test]
    fn single_scattering_quadrature_converges() {
        let (a, b) = (gauss_legendre_unit(128), gauss_legendre_unit(256));
        for (x, y) in [(0.0, 0.0), (0.9, 0.9), (-0.95, 0.3)] {
            let (o, d) = ([x, y, 5.0], [0.0, 0.0, -1.0]);
            let (la, lb) = (single_scattering(o, d, &a), single_scattering(o, d, &b));
            assert!(la > 0.0 && ((la - lb) / lb).abs() < 1e-9, "{la} vs {lb}");
        }
        // A ray missing the cube sees nothing.
        assert_eq!(
            single_scattering([3.0, 0.0, 5.0], [0.0, 0.0, -1.0], &a),
            0.0
        );
    }
}
