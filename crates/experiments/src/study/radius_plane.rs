//! `lt study radius-shrinkage-plane`: Knaus & Zwicker's rates (2011, "Progressive photon mapping:
//! a probabilistic approach") measured where they can be read: ppm at frozen visible points on a
//! diffuse plane under a point light (`scenes/point-plane.toml`), whose radiance is exact,
//! L(x) = (ρ/π) I h / (h² + |x|²)^{3/2}.
//!
//! Why this scene (results/radius-shrinkage/DIAGNOSIS.md): bias must dominate where it is
//! measured, and the answer must be exact at the very points ppm gathers at. Here L has curvature
//! at every point (∇²L = −6 L(0)/h² at the centre), the photons reach the plane once, and the
//! expected estimate of a disc kernel of radius r at x is the disc average D_r(x) of L (K&Z eq. 7
//! with E[Kernel] = the disc average). So with the global schedule r_i² = r_1² Π_{j<i}(j+α)/(j+1)
//! (K&Z eq. 14, r_i² ∝ i^(α−1)) the mean of N passes has, at each point, exactly
//!   bias   b_N = (1/N) Σ_i D_{r_i} − L,
//!   variance V_N = (1/N²) Σ_i (β (ρ/π) Φ D_{r_i} / (π r_i²) − D_{r_i}²) / M,
//! (Φ = 4πI the power of one photon path, M paths a pass): both by quadrature, no reference
//! render. Asymptotically b ≈ (r_N²/8) ∇²L ∝ N^(α−1) (K&Z eq. 18: bias² ∝ N^(−2(1−α))), V ∝
//! N^(−α) (eq. 17), MSE ∝ N^(−min(α, 2(1−α))), best at α = 2/3.
//!
//! The visible points are frozen (`visible_seed`, shared by every run) and recomputed here from
//! the same camera stream, so bias and variance are of the photon part alone; the K runs differ
//! in their photon seeds only (independent streams, never correlated passes).

use super::output::{num, pct, slope_cells, StudyOutput};
use super::{Scale, StudyContext};
use crate::plot::{Chart, Series, Style};
use crate::runs::RunSpec;
use lt_core::sampling::{Domain, Sampler};
use lt_estimators::{jackknife, Image, Jackknifed};
use lt_integrators::radius::global_scale2;
use lt_integrators::visible::{trace_visible_point, CameraPrefix, Direct};
use rayon::prelude::*;
use std::path::PathBuf;

pub const NAME: &str = "radius-shrinkage-plane";
pub const ALPHAS: [f64; 5] = [0.3, 0.5, 2.0 / 3.0, 0.75, 0.9];
/// The three progressive estimators measured at the frozen points. All three are the push
/// estimator of `progressive` at the same points with the same photons; they differ in how the
/// radius shrinks, which is what sets their rates:
/// - `ppm`: Knaus & Zwicker's global schedule r²ᵢ = r²₁ Π_{j<i}(j+α)/(j+1);
/// - sppm's photon part: Hachisuka et al.'s per-point update (r² ← r²(n+αm)/(n+m), n ← n+αm,
///   `radius_update = local`), which is sppm's own, at frozen points — sppm's camera resampling
///   adds a variance of its own, ≈ σ²_pixel / N, computed separately (`camera_variance`);
/// - vcm's merging: vcm's schedule r²ᵢ = r²₁ i^(α−1) (`radius_update = power`), the merge
///   estimator (1/(M π rᵢ²)) Σ β f Φ averaged over passes with weight 1. vcm itself refuses an
///   orthographic camera and its merge kernel sits inside its MIS over connections; run on a
///   pinhole variant, its measured rates would be those of a mixture whose merging weight
///   η = M π rᵢ² itself shrinks with i, plus camera jitter's 1/N. The estimator and schedule are
///   vcm's; the code path is `progressive`'s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RadiusSchedule {
    Ppm,
    SppmPhotons,
    VcmMerging,
}

pub const SCHEDULES: [RadiusSchedule; 3] = [
    RadiusSchedule::Ppm,
    RadiusSchedule::SppmPhotons,
    RadiusSchedule::VcmMerging,
];

impl RadiusSchedule {
    pub fn label(self) -> &'static str {
        match self {
            RadiusSchedule::Ppm => "ppm",
            RadiusSchedule::SppmPhotons => "sppm (photon part)",
            RadiusSchedule::VcmMerging => "vcm (merging)",
        }
    }

    /// ppm's `radius_update` that gives this schedule.
    pub fn update(self) -> &'static str {
        match self {
            RadiusSchedule::Ppm => "global",
            RadiusSchedule::SppmPhotons => "local",
            RadiusSchedule::VcmMerging => "power",
        }
    }

    /// r²ᵢ / r²₁ of a deterministic schedule (None: the per-point update, random).
    pub fn scale2(self, i: u32, alpha: f64) -> Option<f64> {
        match self {
            RadiusSchedule::Ppm => Some(global_scale2(i, alpha)),
            RadiusSchedule::SppmPhotons => None,
            RadiusSchedule::VcmMerging => Some(lt_integrators::radius::power_scale2(i, alpha)),
        }
    }
}

/// The camera pass every run shares: the frozen visible points.
pub const VISIBLE_SEED: u64 = 1;
/// The scene's light and plane (`scenes/point-plane.toml`): intensity I, height h, albedo ρ.
pub const INTENSITY: f64 = std::f64::consts::PI;
pub const HEIGHT: f64 = 1.0;
pub const ALBEDO: f64 = 0.5;
/// Initial radius r_1 = h/2: the disc average at the centre is 15 % below L, so bias² at N = 1 is
/// far above the noise, and r_N stays well inside the 40 × 40 plane.
pub const R1: f64 = 0.5;

pub fn scene(scale: &Scale) -> PathBuf {
    scale.scene_beside_focus("point-plane.toml")
}

/// (runs, passes, photon paths per pass) of the study at a scale. The full scale's are set here
/// (3 estimators × 5 α × 32 runs of 512 passes of 2000 paths: ≈ 40 min of one shared core), the
/// others are the scale's own.
pub fn plane_scale(scale: &Scale) -> (usize, u32, u64) {
    match scale.name {
        "full" => (32, 512, 2000),
        _ => (scale.plane_runs, scale.plane_passes, scale.plane_photons),
    }
}

use super::metrics::alpha_text;

/// The K runs of one estimator and α: photon seeds 1..=K, one shared camera pass.
pub fn config_specs(scale: &Scale, est: RadiusSchedule, alpha: f64) -> Vec<RunSpec> {
    let (runs, n, photons) = plane_scale(scale);
    (0..runs)
        .map(|r| {
            let spec = RunSpec::new(scene(scale), "ppm", 1 + r as u64, n);
            let spec = match est {
                RadiusSchedule::Ppm => spec,
                _ => spec.param("radius_update", est.update()),
            };
            spec.snapshots(Scale::doublings(n))
                .param("alpha", format!("{alpha}"))
                // Photons carry all light: next-event estimation would add a 1/N variance.
                .param("direct", "photons")
                .param("visible_seed", VISIBLE_SEED)
                .param("photons_per_pass", photons)
                .param("radius", R1)
        })
        .collect()
}

pub fn specs(scale: &Scale) -> Vec<RunSpec> {
    SCHEDULES
        .iter()
        .flat_map(|&e| ALPHAS.iter().flat_map(move |&a| config_specs(scale, e, a)))
        .collect()
}

/// The exact radiance at plane point (x, y).
pub fn radiance(x: f64, y: f64) -> f64 {
    let d2 = HEIGHT * HEIGHT + x * x + y * y;
    ALBEDO / std::f64::consts::PI * INTENSITY * HEIGHT / (d2 * d2.sqrt())
}

/// Gauss–Legendre nodes and weights on [0, 1]: the core's rule on [−1, 1], mapped.
pub fn gauss_legendre_unit(n: usize) -> Vec<(f64, f64)> {
    let (nodes, weights) = lt_core::bsdf::quadrature::gauss_legendre(n);
    nodes
        .iter()
        .zip(&weights)
        .map(|(x, w)| (0.5 * (x + 1.0), 0.5 * w))
        .collect()
}

/// Disc averages of L by quadrature: Gauss–Legendre in the radius, the trapezoid rule in angle
/// (spectrally accurate for a smooth periodic integrand). L is analytic with its nearest
/// singularity at distance h, so 24 × 48 nodes reach ~1e-12 relative for r ≤ h/2 (checked
/// against 48 × 96 in the tests below).
pub struct DiscAverage {
    radial: Vec<(f64, f64)>,
    angles: Vec<(f64, f64)>,
}

impl DiscAverage {
    pub fn new(radial: usize, angular: usize) -> DiscAverage {
        DiscAverage {
            radial: gauss_legendre_unit(radial),
            angles: (0..angular)
                .map(|k| {
                    let a = 2.0 * std::f64::consts::PI * k as f64 / angular as f64;
                    (a.cos(), a.sin())
                })
                .collect(),
        }
    }

    /// (1 / π r²) ∫_{|y − x| ≤ r} L(y) dy.
    pub fn at(&self, x: f64, y: f64, r: f64) -> f64 {
        let mut s = 0.0;
        for &(t, w) in &self.radial {
            let rho = t * r;
            let ring: f64 = self
                .angles
                .iter()
                .map(|&(c, si)| radiance(x + rho * c, y + rho * si))
                .sum::<f64>()
                / self.angles.len() as f64;
            // ∫0^r ρ g(ρ) dρ · 2π / (π r²) = 2 ∫0^1 t g(t r) dt
            s += 2.0 * w * t * ring;
        }
        s
    }
}

/// One frozen visible point: where it is and the camera weight β its photons are scaled by.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    pub pixel: usize,
    pub x: f64,
    pub y: f64,
    pub beta: f64,
}

/// The visible points ppm draws from `VISIBLE_SEED`, recomputed from the same streams as
/// `ppm`'s camera pass (pixel j: the camera domain's stream (seed, j, pass 0)).
pub fn visible_points(spec: &RunSpec) -> Result<Vec<Point>, String> {
    let scene = spec.load_scene()?;
    let max_depth = scene.settings.max_depth;
    Ok((0..scene.camera.pixel_count())
        .filter_map(|j| {
            let mut s = Sampler::for_item(Domain::Camera, VISIBLE_SEED, j as u64, 0);
            let film = lt_integrators::pixel::pixel_sample(&scene, j as u64, &mut s);
            let pre = CameraPrefix::weighted(film.map(|f| {
                let p = trace_visible_point(&scene, f.raster, &mut s, max_depth, Direct::Photons);
                (p, f.weight)
            }));
            pre.vp.map(|vp| Point {
                pixel: j,
                x: vp.gp.p.x as f64,
                y: vp.gp.p.y as f64,
                beta: vp.gp.beta.x as f64,
            })
        })
        .collect())
}

/// Exact bias and variance of the N-pass mean at every point and snapshot: `[snapshot][point]`.
pub struct Exact {
    pub value: Vec<f64>,
    pub bias: Vec<Vec<f64>>,
    pub variance: Vec<Vec<f64>>,
}

pub fn exact(
    points: &[Point],
    est: RadiusSchedule,
    alpha: f64,
    photons: u64,
    snaps: &[u32],
) -> Exact {
    let q = DiscAverage::new(24, 48);
    let last = *snaps.last().unwrap_or(&1);
    // β (ρ/π) Φ with Φ = 4πI: one photon path's contribution before the kernel 1/(π r²).
    let c = ALBEDO / std::f64::consts::PI * 4.0 * std::f64::consts::PI * INTENSITY;
    let per_point: Vec<(f64, Vec<f64>, Vec<f64>)> = points
        .par_iter()
        .map(|p| {
            let l = p.beta * radiance(p.x, p.y);
            let (mut sd, mut sv) = (0.0, 0.0);
            let (mut b, mut v) = (Vec::new(), Vec::new());
            for i in 1..=last {
                // The per-point update has no deterministic radius: no exact model.
                let Some(scale2) = est.scale2(i, alpha) else {
                    if snaps.contains(&i) {
                        b.push(f64::NAN);
                        v.push(f64::NAN);
                    }
                    continue;
                };
                // The integrator's radius is an f32 (r_1 · r_1 · scale, rounded once).
                let r2 = ((R1 as f32 * R1 as f32) as f64 * scale2) as f32 as f64;
                let d = p.beta * q.at(p.x, p.y, r2.sqrt());
                sd += d;
                sv += (p.beta * c * d / (std::f64::consts::PI * r2) - d * d) / photons as f64;
                if snaps.contains(&i) {
                    let n = i as f64;
                    b.push(sd / n - l);
                    v.push(sv / (n * n));
                }
            }
            (l, b, v)
        })
        .collect();
    let mut e = Exact {
        value: per_point.iter().map(|p| p.0).collect(),
        bias: vec![Vec::new(); snaps.len()],
        variance: vec![Vec::new(); snaps.len()],
    };
    for (_, b, v) in &per_point {
        for k in 0..snaps.len() {
            e.bias[k].push(b[k]);
            e.variance[k].push(v[k]);
        }
    }
    e
}

/// (bias², variance) averaged over the points from the runs `kept` at one snapshot
/// (`values[run][point]`): per point (m − L)² − s²/K, an unbiased estimate of b², and s².
pub fn bias2_variance(values: &[Vec<f64>], kept: &[usize], exact: &[f64]) -> (f64, f64) {
    let k = kept.len() as f64;
    let (mut b2, mut var) = (0.0, 0.0);
    for (p, l) in exact.iter().enumerate() {
        let m = kept.iter().map(|&r| values[r][p]).sum::<f64>() / k;
        let s2 = kept
            .iter()
            .map(|&r| (values[r][p] - m).powi(2))
            .sum::<f64>()
            / (k - 1.0);
        b2 += (m - l).powi(2) - s2 / k;
        var += s2;
    }
    let n = exact.len().max(1) as f64;
    (b2 / n, var / n)
}

/// Predicted log-log slopes against N: (variance, bias², MSE).
pub fn predicted(alpha: f64) -> (f64, f64, f64) {
    (
        -alpha,
        -2.0 * (1.0 - alpha),
        -alpha.min(2.0 * (1.0 - alpha)),
    )
}

pub fn slope(xs: &[f64], ys: &[f64]) -> Result<f64, String> {
    if let Some(y) = ys.iter().find(|y| !(**y > 0.0)) {
        return Err(format!("value {y:.3e} ≤ 0 in the tail"));
    }
    let ly: Vec<f64> = ys.iter().map(|y| y.ln()).collect();
    lt_estimators::fit_line(xs, &ly, 0.95).map(|f| f.slope)
}

/// One α's measurement.
pub struct Measured {
    pub schedule: RadiusSchedule,
    pub alpha: f64,
    pub snaps: Vec<u32>,
    /// Per snapshot: measured (bias², variance, MSE) with jackknife intervals.
    pub at_n: Vec<[Jackknifed; 3]>,
    /// Per snapshot: exact (bias², variance, MSE) averaged over the points.
    pub exact_at_n: Vec<[f64; 3]>,
    /// Slopes over the tail: measured (jackknifed) and exact, for bias², variance, MSE.
    pub slopes: [Result<Jackknifed, String>; 3],
    pub exact_slopes: [f64; 3],
    pub tail: Vec<u32>,
    /// Render time of the K runs as their records state it.
    pub seconds: f64,
}

pub fn measure(ctx: &StudyContext, est: RadiusSchedule, alpha: f64) -> Result<Measured, String> {
    let scale = &ctx.scale;
    let specs = config_specs(scale, est, alpha);
    let entries = ctx.run_all(&specs)?;
    let points = visible_points(&specs[0])?;
    let snaps = specs[0].snapshots.clone();
    let ex = exact(&points, est, alpha, plane_scale(scale).2, &snaps);
    // values[snapshot][run][point]: channel 0 (grey scene: every channel is the same).
    let values: Vec<Vec<Vec<f64>>> = snaps
        .iter()
        .map(|&n| {
            entries
                .iter()
                .map(|e| {
                    let img: Image = e.snapshot(n)?;
                    Ok(points.iter().map(|p| img.data[p.pixel][0]).collect())
                })
                .collect::<Result<_, String>>()
        })
        .collect::<Result<_, String>>()?;
    let measured = measured_rates(&values, &ex.value, &snaps, scale.confidence)?;
    let np = points.len().max(1) as f64;
    let exact_at_n: Vec<[f64; 3]> = (0..snaps.len())
        .map(|k| {
            let b2 = ex.bias[k].iter().map(|b| b * b).sum::<f64>() / np;
            let v = ex.variance[k].iter().sum::<f64>() / np;
            [b2, v, b2 + v]
        })
        .collect();
    let tail_idx = &measured.tail_idx;
    let xs: Vec<f64> = tail_idx.iter().map(|&k| (snaps[k] as f64).ln()).collect();
    let exact_slope = |which: usize| {
        let ys: Vec<f64> = tail_idx.iter().map(|&k| exact_at_n[k][which]).collect();
        slope(&xs, &ys).unwrap_or(f64::NAN)
    };
    let exact_slopes = [exact_slope(0), exact_slope(1), exact_slope(2)];
    Ok(Measured {
        seconds: entries
            .iter()
            .filter_map(|e| e.record.seconds.last().copied())
            .sum(),
        schedule: est,
        alpha,
        tail: tail_idx.iter().map(|&k| snaps[k]).collect(),
        snaps,
        at_n: measured.at_n,
        exact_at_n,
        slopes: measured.slopes,
        exact_slopes,
    })
}

/// What K independent runs show at one set of points: per snapshot (bias², variance, MSE) with
/// jackknife intervals, and their log-log slopes against N over the tail (N ≥ last / 8).
pub struct MeasuredRates {
    pub at_n: Vec<[Jackknifed; 3]>,
    pub slopes: [Result<Jackknifed, String>; 3],
    /// Indices of the tail's snapshots.
    pub tail_idx: Vec<usize>,
}

/// `values[snapshot][run][point]` against the exact `target[point]` (the plane's radiance here,
/// a medium's single scattering in `radius_media`).
pub fn measured_rates(
    values: &[Vec<Vec<f64>>],
    target: &[f64],
    snaps: &[u32],
    conf: f64,
) -> Result<MeasuredRates, String> {
    let runs = values.first().map_or(0, Vec::len);
    let mut at_n = Vec::new();
    for vals in values {
        let stat = |which: usize| {
            jackknife(runs, conf, |kept| {
                let (b, v) = bias2_variance(vals, kept, target);
                Ok([b, v, b + v][which])
            })
        };
        at_n.push([stat(0)?, stat(1)?, stat(2)?]);
    }
    let last = *snaps.last().unwrap_or(&1);
    let tail_idx: Vec<usize> = (0..snaps.len()).filter(|&k| 8 * snaps[k] >= last).collect();
    let xs: Vec<f64> = tail_idx.iter().map(|&k| (snaps[k] as f64).ln()).collect();
    let measured_slope = |which: usize| {
        jackknife(runs, conf, |kept| {
            let ys: Vec<f64> = tail_idx
                .iter()
                .map(|&k| {
                    let (b, v) = bias2_variance(&values[k], kept, target);
                    [b, v, b + v][which]
                })
                .collect();
            slope(&xs, &ys)
        })
    };
    Ok(MeasuredRates {
        at_n,
        slopes: [measured_slope(0), measured_slope(1), measured_slope(2)],
        tail_idx,
    })
}

const QUANTITIES: [&str; 3] = ["bias²", "variance", "MSE"];

/// sppm's camera part: the pixel variance of L, mean over the pixels (orthographic camera over
/// [−1, 1]², box filter: each pixel a square of the plane, its visible point uniform in it). A
/// pass of sppm draws a new point per pixel, so its estimate has this variance on top of the
/// photon part's, and the mean of N passes ≈ σ²_pixel / N (D_{rᵢ} is smoother than L: a bound).
pub fn camera_variance(width: usize) -> f64 {
    let q = gauss_legendre_unit(8);
    let step = 2.0 / width as f64;
    let mut total = 0.0;
    for py in 0..width {
        for px in 0..width {
            let (x0, y0) = (-1.0 + px as f64 * step, -1.0 + py as f64 * step);
            let (mut m1, mut m2) = (0.0, 0.0);
            for &(u, wu) in &q {
                for &(v, wv) in &q {
                    let l = radiance(x0 + u * step, y0 + v * step);
                    m1 += wu * wv * l;
                    m2 += wu * wv * l * l;
                }
            }
            total += m2 - m1 * m1;
        }
    }
    total / (width * width) as f64
}

pub fn run(ctx: &StudyContext) -> Result<(), String> {
    let scale = &ctx.scale;
    let t0 = std::time::Instant::now();
    let mut ms: Vec<Measured> = Vec::new();
    for est in SCHEDULES {
        for a in ALPHAS {
            ms.push(measure(ctx, est, a)?);
        }
    }
    let first_spec = &config_specs(scale, RadiusSchedule::Ppm, ALPHAS[0])[0];
    let points = visible_points(first_spec)?.len();
    let width = first_spec.load_scene()?.camera.width as usize;
    let mut out = StudyOutput::new(
        ctx.study_dir(NAME),
        NAME,
        "Radius shrinkage at exact points: Knaus & Zwicker's rates measured",
        scale,
    )?;
    describe(&mut out, &ms, scale, points);
    rates_table(&mut out, &ms)?;
    sppm_camera_part(&mut out, &ms, width);
    exact_check(&mut out, &ms, scale)?;
    quantity_charts(&mut out, &ms)?;
    rate_chart(&mut out, &ms)?;
    ctx.say(&format!(
        "{NAME}: analysis {:.1} s",
        t0.elapsed().as_secs_f64()
    ));
    out.finish()
}

/// The study's opening paragraph: the estimators, the scene, the runs and how they are judged.
fn describe(out: &mut StudyOutput, ms: &[Measured], scale: &Scale, points: usize) {
    let seconds: f64 = ms.iter().map(|m| m.seconds).sum();
    let tail = &ms[0].tail;
    out.para(&format!(
        "Three progressive estimators on `point-plane` (a diffuse plane under a point light at \
         height h = 1, radiance exact: L = (ρ/π) I h / (h² + |x|²)^(3/2)) at {points} frozen \
         visible points (one camera pass shared by every run), {k} independent runs (photon seeds \
         1…{k}) of {n} passes of {m} photon paths, r_1 = {r1} h, all light from photons, for α ∈ \
         {{0.3, 0.5, 2/3, 0.75, 0.9}}: **ppm** (Knaus & Zwicker's global schedule r²ᵢ = r²₁ \
         Π_{{j<i}}(j+α)/(j+1)); **sppm's photon part** (sppm's own per-point update, r² ← \
         r²(n+αm)/(n+m), at the same frozen points; its camera resampling is stated separately \
         below); **vcm's merging** (vcm's schedule r²ᵢ = r²₁ i^(α−1), the merge estimator \
         1/(M π rᵢ²) Σ β f Φ with weight 1, at the same points). Why vcm's merging is measured at \
         frozen points and not through `lt render vcm`: vcm refuses an orthographic camera, and on \
         a pinhole variant its merging is one technique of an MIS whose merging weight η = M π \
         rᵢ² itself shrinks with i, with the camera's jitter on top — the rates of that mixture \
         are not K&Z's. The reference is exact at each point, and so are the bias and variance \
         K&Z's model gives at each N for the two deterministic schedules (disc averages of L by \
         quadrature, see the module's doc); the per-point update's radius is random, so sppm's \
         rows are compared with the asymptotic rates only. bias² = mean over points of (m − L)² \
         − s²/K, variance = mean of s², MSE = their sum; intervals are {c} % delete-one \
         jackknife over runs; slopes are fitted over N ∈ {{{tail}}}. **Compute:** {secs:.0} s of \
         render time as recorded ({k} runs × 5 α × 3 estimators, niced, on a 2-core machine \
         shared with two other jobs).",
        k = plane_scale(scale).0,
        n = plane_scale(scale).1,
        m = plane_scale(scale).2,
        r1 = R1,
        c = pct(scale.confidence),
        tail = tail
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        secs = seconds,
    ));
}

/// The slope table: the columns tests/studies.rs reads.
fn rates_table(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    let mut rows = Vec::new();
    for m in ms {
        let (pv, pb, pm) = predicted(m.alpha);
        for (q, asymptotic) in [(0, pb), (1, pv), (2, pm)] {
            let pred = m.exact_slopes[q];
            let have_exact = pred.is_finite();
            let against = if have_exact { pred } else { asymptotic };
            let (meas, ci, diff, inside) = slope_cells(&m.slopes[q], against);
            let asym_inside = match &m.slopes[q] {
                Ok(j) => yes_no(j.interval.contains(asymptotic)),
                Err(_) => "—".into(),
            };
            rows.push(vec![
                m.schedule.label().into(),
                alpha_text(m.alpha),
                QUANTITIES[q].into(),
                meas,
                ci,
                num(asymptotic),
                if have_exact { num(pred) } else { "—".into() },
                diff,
                inside,
                asym_inside,
            ]);
        }
    }
    out.table(
        "rates",
        "Measured slopes against Knaus & Zwicker's",
        "Slope of ln(quantity) against ln N over the tail with its jackknife interval; K&Z's \
         asymptotic rate; the exact slope of their model at these N (bias and variance by \
         quadrature with the integrator's own radius schedule, which still holds r_N's \
         higher-order terms and the finite-N sums; — for the per-point update, whose radius is \
         random); difference from the latter (else from the asymptotic rate) ± half-width; \
         whether the interval contains the exact rate at these N, else the asymptotic one \
         (`inside`), and the asymptotic one (`inside asymptotic`).",
        &[
            "integrator",
            "α",
            "quantity",
            "measured",
            "CI",
            "predicted",
            "predicted at these N",
            "difference",
            "inside",
            "inside asymptotic",
        ],
        rows,
        true,
    )
}

/// sppm's camera part, stated separately: its 1/N against the photon part's variance.
fn sppm_camera_part(out: &mut StudyOutput, ms: &[Measured], width: usize) {
    let sigma2 = camera_variance(width);
    let last = *ms[0].snaps.last().unwrap_or(&1);
    let photon_var: Vec<(f64, f64)> = ms
        .iter()
        .filter(|m| m.schedule == RadiusSchedule::SppmPhotons)
        .map(|m| (m.alpha, m.at_n.last().map_or(f64::NAN, |j| j[1].estimate)))
        .collect();
    out.para(&format!(
        "**sppm's camera part.** sppm draws a new visible point per pixel each pass; with the \
         photon part measured above, its variance adds the pixel variance of L, σ²_pixel = {s} \
         (mean over the {w}×{w} pixels, by quadrature), as ≈ σ²_pixel / N: {cam} at N = {last}, \
         against the photon part's {pv} there. It falls at rate 1, faster than the photon part's \
         α, so on this scene it never sets sppm's rate; where it dominates a measurement (small \
         radii, smooth light) sppm's variance slope reads ≈ −1 whatever α, as \
         results/radius-shrinkage found on sun-room.",
        s = num(sigma2),
        w = width,
        cam = num(sigma2 / last as f64),
        pv = photon_var
            .iter()
            .map(|(a, v)| format!("{} (α = {})", num(*v), alpha_text(*a)))
            .collect::<Vec<_>>()
            .join(", "),
    ));
}

/// Every snapshot: the measured bias² and variance against the exact ones, at a Bonferroni
/// level so that the table's many checks miss by luck with ≈ 5 % in all.
fn exact_check(out: &mut StudyOutput, ms: &[Measured], scale: &Scale) -> Result<(), String> {
    let exact_ms: Vec<&Measured> = ms
        .iter()
        .filter(|m| m.exact_slopes[0].is_finite())
        .collect();
    let checks = exact_ms.iter().map(|m| 2 * m.snaps.len()).sum::<usize>();
    let strict = 1.0 - (1.0 - scale.confidence) / checks as f64;
    let mut exact_rows = Vec::new();
    let mut misses = 0;
    for m in &exact_ms {
        for (k, &n) in m.snaps.iter().enumerate() {
            for (q, &quantity) in QUANTITIES.iter().enumerate().take(2) {
                let j = &m.at_n[k][q];
                let z = lt_estimators::bias_variance::t_quantile(strict, (j.runs - 1) as f64);
                let (lo, hi) = (j.estimate - z * j.std_error, j.estimate + z * j.std_error);
                let e = m.exact_at_n[k][q];
                let inside = lo <= e && e <= hi;
                misses += usize::from(!inside);
                exact_rows.push(vec![
                    m.schedule.label().into(),
                    alpha_text(m.alpha),
                    n.to_string(),
                    quantity.into(),
                    num(j.estimate),
                    format!("[{}, {}]", num(lo), num(hi)),
                    num(e),
                    num((j.estimate - e) / j.std_error),
                    yes_no(inside),
                ]);
            }
        }
    }
    out.para(&format!(
        "**Exact check.** At every N and α the measured bias² and variance of ppm and vcm's \
         merging are compared with the model's exact values at the same points ({checks} checks \
         at {} % each, Bonferroni for 95 % in all): {} outside. A wrong normalisation, radius \
         schedule or kernel would show here at N = 1 already, where bias² is {} standard errors \
         above 0.",
        num(strict * 100.0),
        misses,
        num(exact_ms
            .iter()
            .map(|m| m.at_n[0][0].estimate / m.at_n[0][0].std_error)
            .fold(f64::INFINITY, f64::min)),
    ));
    out.table(
        "exact",
        "Measured bias² and variance against the exact model, every N",
        "Measured value, its Bonferroni-level interval, the exact value at the same points, \
         the difference in standard errors, and whether the interval holds it.",
        &[
            "integrator",
            "α",
            "N",
            "quantity",
            "measured",
            "CI",
            "exact",
            "z",
            "inside",
        ],
        exact_rows,
        false,
    )
}

/// bias², variance and MSE against N, one chart each, every estimator and α with its exact curve.
fn quantity_charts(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    for (q, file) in [(0, "bias2"), (1, "variance"), (2, "mse")] {
        let mut series = Vec::new();
        for m in ms {
            let tag = format!("{}, α = {}", m.schedule.label(), alpha_text(m.alpha));
            series.push(Series {
                name: tag.clone(),
                points: m
                    .snaps
                    .iter()
                    .zip(&m.at_n)
                    .map(|(&n, j)| (n as f64, j[q].estimate))
                    .collect(),
                y_interval: m
                    .at_n
                    .iter()
                    .map(|j| (j[q].interval.lo, j[q].interval.hi))
                    .collect(),
                style: Style::Measured,
            });
            if m.exact_slopes[0].is_finite() {
                series.push(Series {
                    name: format!("exact, {tag}"),
                    points: m
                        .snaps
                        .iter()
                        .zip(&m.exact_at_n)
                        .map(|(&n, e)| (n as f64, e[q]))
                        .collect(),
                    y_interval: Vec::new(),
                    style: Style::Fitted,
                });
            }
        }
        out.chart(
            file,
            &Chart {
                title: format!(
                    "ppm, sppm's photon part, vcm's merging on point-plane: {} against passes",
                    QUANTITIES[q]
                ),
                x_label: "passes N".into(),
                y_label: QUANTITIES[q].into(),
                log_x: true,
                log_y: true,
                series,
            },
            &format!(
                "{} of one run against N per estimator and α (points: measured, jackknife \
                 intervals; dashed: exact by quadrature where the schedule is deterministic).",
                QUANTITIES[q]
            ),
        )?;
    }
    Ok(())
}

/// The lecture's figure: MSE rate against α, all three estimators (shifted by ±0.01 in α so
/// their intervals do not overlap), K&Z's curve through them; and how to read it.
fn rate_chart(out: &mut StudyOutput, ms: &[Measured]) -> Result<(), String> {
    let curve: Vec<(f64, f64)> = (0..=100)
        .map(|i| {
            let a = 0.2 + 0.8 * i as f64 / 100.0;
            (a, a.min(2.0 * (1.0 - a)))
        })
        .collect();
    let mut series = Vec::new();
    for (e, shift) in SCHEDULES.iter().zip([-0.01, 0.0, 0.01]) {
        let measured: Vec<(f64, f64, (f64, f64))> = ms
            .iter()
            .filter(|m| m.schedule == *e)
            .filter_map(|m| {
                m.slopes[2].as_ref().ok().map(|j| {
                    (
                        m.alpha + shift,
                        -j.estimate,
                        (-j.interval.hi, -j.interval.lo),
                    )
                })
            })
            .collect();
        series.push(Series {
            name: format!("measured: {}", e.label()),
            points: measured.iter().map(|m| (m.0, m.1)).collect(),
            y_interval: measured.iter().map(|m| m.2).collect(),
            style: Style::Measured,
        });
    }
    series.push(Series {
        name: "min(α, 2(1−α)) (asymptotic)".into(),
        points: curve,
        y_interval: Vec::new(),
        style: Style::Fitted,
    });
    series.push(Series {
        name: "K&Z's model at these N, ppm's schedule (exact)".into(),
        points: ms
            .iter()
            .filter(|m| m.schedule == RadiusSchedule::Ppm)
            .map(|m| (m.alpha, -m.exact_slopes[2]))
            .collect(),
        y_interval: Vec::new(),
        style: Style::Fitted,
    });
    out.chart(
        "mse-rate",
        &Chart {
            title: "MSE rate against α (K&Z: min(α, 2(1−α)))".into(),
            x_label: "α".into(),
            y_label: "MSE rate (−slope of ln MSE against ln N)".into(),
            log_x: false,
            log_y: false,
            series,
        },
        "−(MSE slope) per α with its jackknife interval for ppm, sppm's photon part and vcm's \
         merging (drawn at α − 0.01, α, α + 0.01); the curve is K&Z's asymptotic rate, best at \
         α = 2/3; the dashed points are their model's exact slope over the same N (ppm's \
         schedule).",
    )?;
    out.para(
        "**Reading the MSE-rate figure.** Where the measured rates sit above min(α, 2(1−α)) — \
         most at α = 0.5, whose bias² (rate 1) and variance (rate 0.5) are still of comparable \
         size at these N — the MSE is a sum of two power laws and its local slope lies between \
         them until the slower one dominates; the asymptotic curve is its limit as N → ∞, and \
         the exact model at these N (`predicted at these N`) is what the intervals are held to. \
         Left of 2/3 the variance sets the asymptotic rate (α), right of it bias² (2(1−α)). \
         Asymptotic slopes are missed by a few hundredths where the intervals are that narrow \
         (`inside asymptotic`): r_1 = h/2 keeps the O(r⁴) term of the disc average visible \
         (K&Z's bias ≈ (r²/8)∇²L is its first term).",
    );
    Ok(())
}

fn yes_no(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrature_is_exact_enough() {
        // The centred disc average has a closed form: 2 ρ I h / (π r²) · (1/h − 1/√(h² + r²))
        // · π / π … i.e. (ρ/π) I · 2h/r² · (1/h − 1/√(h²+r²)).
        let q = DiscAverage::new(24, 48);
        for r in [0.01, 0.1, 0.5] {
            let exact = ALBEDO / std::f64::consts::PI * INTENSITY * 2.0 * HEIGHT / (r * r)
                * (1.0 / HEIGHT - 1.0 / (HEIGHT * HEIGHT + r * r).sqrt());
            let got = q.at(0.0, 0.0, r);
            assert!(
                ((got - exact) / exact).abs() < 1e-10,
                "r {r}: {got} vs {exact}"
            );
        }
        // Off centre: against a finer rule.
        let fine = DiscAverage::new(48, 96);
        for (x, y) in [(0.7, 0.2), (-0.9, 0.9)] {
            let (a, b) = (q.at(x, y, 0.5), fine.at(x, y, 0.5));
            assert!(((a - b) / b).abs() < 1e-12, "{a} vs {b}");
        }
    }
}
