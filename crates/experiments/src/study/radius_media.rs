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
//! table). pp3d's free-flight choice of its query point on that ray still adds a 1/N term of its
//! own, which falls faster than N^(−α) for α < 1 but can set the slope at finite N.

use super::metrics::alpha_text;
use super::output::{num, pct, slope_cells, StudyOutput};
use super::radius_plane::{gauss_legendre_unit, measured_rates, MeasuredRates};
use super::{Scale, StudyContext};
use crate::runs::RunSpec;
use lt_core::Vec2;
use lt_estimators::Image;
use lt_integrators::volume_density::schedule::{balanced_alpha, predicted_rates};
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

/// (runs, passes, photon-path divisor) at a scale. results/points-beams.md reports the quick
/// scale (≈ 9 s CPU); the committed and full scales (16 runs of 256 passes, 10× the photons)
/// take longer than 20 CPU min on a shared 2-core machine (pb2d at α = 0.9 keeps r ≈ r₁).
pub fn media_scale(scale: &Scale) -> (usize, u32, u64) {
    match scale.name {
        "full" | "committed" => (16, 256, 1),
        "test" => (4, 8, 100),
        _ => (8, 64, 10),
    }
}

/// Photon paths per pass of each estimator at the committed scale (divided by the scale's
/// divisor): a kernel of lower dimension gathers from more of them per query. pp3d's are few on
/// purpose: its free-flight query point adds a 1/N variance that at 10⁵ paths hides the
/// photons' N^(−α) (quick scale: variance slope ≈ −1 at every α), at 5,000 less so.
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

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    ESTIMATORS
        .iter()
        .flat_map(|&(e, d)| {
            alphas(d)
                .into_iter()
                .flat_map(move |a| config_specs(scale, e, a))
        })
        .collect()
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
    })
}

const QUANTITIES: [&str; 3] = ["bias²", "variance", "MSE"];

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let first = &config_specs(scale, "pp3d", 0.5)[0];
    let (exact, pixel_var) = exact_pixels(first, 8, 128)?;
    // The quadrature's own error: against a finer rule on both axes.
    let (finer, _) = exact_pixels(first, 12, 256)?;
    let quadrature_error = exact
        .iter()
        .zip(&finer)
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0.0, f64::max);
    let mut ms = Vec::new();
    for (e, d) in ESTIMATORS {
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
         N^(−4(1−α)/d). The camera samples the pixel's centre ray (a box filter of 1/500 pixel: \
         its own variance σ²_pixel/N = {s2}/N); pp3d's free-flight query point adds a 1/N term \
         of its own, faster than N^(−α) asymptotically but visible at these N. Render CPU: \
         {cpu:.0} s.",
        mean = num(mean_l),
        qe = num(quadrature_error),
        c = pct(scale.confidence),
        tail = (passes / 8).max(1),
        s2 = num(sigma2),
    ));
    let mut rows = Vec::new();
    for m in &ms {
        let (pv, pb) = predicted_rates(m.alpha, m.d);
        let pm = pv.max(pb);
        for (q, pred) in [(0, pb), (1, pv), (2, pm)] {
            let (meas, ci, diff, inside) = slope_cells(&m.rates.slopes[q], pred);
            let last = m.rates.at_n.last().map(|j| &j[q]);
            rows.push(vec![
                m.estimator.into(),
                m.d.to_string(),
                alpha_text(m.alpha),
                QUANTITIES[q].into(),
                meas,
                ci,
                num(pred),
                diff,
                inside,
                last.map_or("—".into(), |j| num(j.estimate)),
                last.map_or("—".into(), |j| num(j.std_error)),
            ]);
        }
    }
    out.table(
        "rates",
        "Measured slopes against the predicted rates",
        "Slope of ln(quantity) against ln N over the tail with its jackknife interval; the \
         predicted asymptotic rate (schedule.rs; MSE: the slower of the two); difference ± \
         half-width; whether the interval holds the prediction; the quantity and its standard \
         error at the last N. A `—` slope: the quantity is not resolved from zero in the tail \
         (bias² below the runs' noise).",
        &[
            "integrator",
            "d",
            "α",
            "quantity",
            "measured",
            "CI",
            "predicted",
            "difference",
            "inside",
            "at last N",
            "± (1 s.e.)",
        ],
        rows,
        true,
    )?;
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
            ]);
        }
    }
    out.table(
        "per-n",
        "bias² and variance at every N",
        "Mean over pixels, with one jackknife standard error.",
        &[
            "integrator",
            "α",
            "N",
            "bias²",
            "± bias²",
            "variance",
            "± variance",
        ],
        per_n,
        false,
    )?;
    out.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

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
